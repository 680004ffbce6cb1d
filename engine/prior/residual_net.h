// The residual prior's network: a small U-Net that predicts, from a blurry image and the events
// of its exposure, the residuals R(t_i) = I(t_i) - I(t_N) of the 2N+1 virtual frames (linear RGB,
// the middle frame t_N excluded: its residual is zero).
//
// Input (3 + 2 * 2N channels, planar): the blurry linear RGB image, then per non-middle frame i
// (in frame order) the accumulation E[t_N, t_i] of each polarity (prior/event_inputs.h).
// Output (3 * 2N channels): per non-middle frame, R(t_i) as linear RGB.
//
//   enc0   3x3 s1  in -> w      ReLU   full size   (skip 0)
//   down1  3x3 s2  w -> 2w      ReLU   half
//   enc1   3x3 s1  2w -> 2w     ReLU   half        (skip 1)
//   down2  3x3 s2  2w -> 4w     ReLU   quarter
//   enc2   3x3 s1  4w -> 4w     ReLU   quarter
//   dec1   x2 up, [up; skip 1]  6w -> 2w   3x3 s1 ReLU   half
//   dec0   x2 up, [up; skip 0]  3w -> w    3x3 s1 ReLU   full
//   out    1x1     w -> 3 * 2N   (no activation; zero-initialised, so training starts at R = 0)
//
// Forward and backward compose engine/nn's layers; the activations are owned for one input size.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "nn/conv2d.h"
#include "nn/safetensors.h"

namespace evflow::prior {

struct ResidualNetSpec {
  uint32_t frames = 7;  // 2N + 1 virtual frames
  uint32_t width = 16;  // channels of the full-size layers (w above)
  uint32_t residuals() const { return frames - 1; }
  uint32_t in_channels() const { return 3 + 2 * residuals(); }
  uint32_t out_channels() const { return 3 * residuals(); }
  std::string str() const;  // "residual-unet frames=7 width=16"
};

class ResidualNet {
 public:
  // Throws std::invalid_argument for an even or single frame count or a zero width.
  ResidualNet(gpu::Context& ctx, const ResidualNetSpec& spec, uint32_t height, uint32_t width);

  const ResidualNetSpec& spec() const { return spec_; }
  uint32_t height() const { return input_.shape().h; }
  uint32_t width() const { return input_.shape().w; }
  uint64_t parameter_count() const;
  std::vector<nn::Conv2d*> layers();

  nn::Tensor& input() { return input_; }               // where the caller uploads the input
  const nn::Tensor& output() const { return out_.z; }  // after forward()
  nn::Tensor& output_grad() { return out_.grad; }      // d(loss)/d(output), before backward()
  const nn::Tensor& input_grad() const { return input_grad_; }

  void init_he(uint64_t seed);  // layer i from seed + i; the output layer zero
  void forward(gpu::Commands& cmd);
  // input_grad: also d(loss)/d(input); accumulate_params: add to the parameter gradients (the
  // samples of a batch).
  void backward(gpu::Commands& cmd, bool input_grad, bool accumulate_params);
  void add_to(Adam& adam, float lr);

  // Tensors "prior.<layer>.weight" / ".bias"; metadata "architecture" = spec().str().
  nn::SafetensorsFile save() const;
  // Throws std::runtime_error naming `source` when the architecture or a tensor's shape differs
  // or a tensor is missing.
  void load(const nn::SafetensorsFile& file, const std::string& source);
  // The same weights (a network of the same spec, possibly another size).
  void copy_weights_from(const ResidualNet& other);

 private:
  struct Level {  // a convolution, its output and ReLU, and their gradients
    std::unique_ptr<nn::Conv2d> conv;
    nn::Tensor z, a, grad;
  };
  Level make_level(gpu::Context& ctx, nn::ConvSpec s, const std::string& name, nn::Shape in, bool relu);
  void conv_backward(gpu::Commands& cmd, Level& l, const nn::Tensor& in, const nn::Tensor* dx, bool accumulate_input,
                     bool accumulate_params);

  ResidualNetSpec spec_;
  nn::Tensor input_, input_grad_;
  Level enc0_, down1_, enc1_, down2_, enc2_, dec1_, dec0_, out_;
  nn::Tensor up1_, cat1_, up0_, cat0_;  // decoder inputs
  nn::Tensor up1_grad_, cat1_grad_, up0_grad_, cat0_grad_;
};

// Loads a network from a safetensors file written by ResidualNet::save, sized height x width.
std::unique_ptr<ResidualNet> load_residual_net(gpu::Context& ctx, const std::string& path, uint32_t height,
                                               uint32_t width);

}  // namespace evflow::prior
