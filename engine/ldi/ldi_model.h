// The learnable double integral (paper Sec. 4.5, Eq. 8; docs/ldi.md): per frame time t_i of an
// exposure [t_0, t_2N] (T = t_2N - t_0), over a crop of the view,
//
//   E(t_i) = softplus(w1 LDI(P(E[t_i, t_0])) + w2 LDI(P(E[t_i, t_2N]))) + kLdiFloor,
//   w1 = (t_i - t_0) / T,  w2 = (t_2N - t_i) / T,
//   C_ldi(t_i)[c] = B[c] / E(t_i)   for each colour channel c of the blurry crop B (linear light),
//
// with LDI a ConvStack (3x3 convolutions, ReLU between; widths 32 -> ... -> 1) shared by both
// sides and every frame, and P the event tensors of engine/ldi/event_bins.h. A side with weight 0
// (t_i at an end of the exposure) is not run.
//
// The calls of a forward (2F - 2 for F frames, fewer when a frame lies at an end of the exposure)
// run as one batch of the network, one dispatch per layer, when the batch's activations fit
// (batch_for()); otherwise in chunks of that many calls. The backward uses the activations the
// forward left (the last chunk's) and runs every other chunk's forward again before its backward;
// the weight gradients of all calls are summed (Conv2d's accumulate_params).
#pragma once
#include <cstdint>
#include <string>
#include <vector>

#include "events/gpu_events.h"
#include "gpu/commands.h"
#include "ldi/event_bins.h"
#include "ldi/ldi_layout.h"
#include "nn/conv_stack.h"
#include "nn/safetensors.h"
#include "optim/adam.h"

namespace evflow::ldi {

// The bias of the last layer that makes E = 1 where a side has no events (B / E = B).
float neutral_bias();

// A regression of log E to a target D added to a backward from the frames: scale * sum
// (log E(t_i) - log D_i)^2 (training's tie to EDI's integral, train/ldi_branch.h).
struct LdiAnchor {
  const gpu::Buffer* target = nullptr;  // D, F x crop
  float scale = 0;
};

class LdiModel {
 public:
  // widths: 32, the hidden layers' widths, 1. crop_w x crop_h: the size of every crop it runs on;
  // max_frames: the most frame times per forward. max_batch: the most calls per chunk (0: as
  // many as batch_for allows).
  LdiModel(gpu::Context& ctx, const GpuEvents& events, const std::vector<uint32_t>& widths, uint32_t crop_w,
           uint32_t crop_h, uint32_t max_frames, uint32_t max_batch = 0);

  // Calls per chunk for a network of these widths on crops of crop_w x crop_h: all 2 max_frames
  // calls where their activations fit kLdiActivationBytes and the widest tensor one storage
  // binding of the device, else as many as do (at least 1).
  static uint32_t batch_for(const gpu::Context& ctx, const std::vector<uint32_t>& widths, uint32_t crop_w,
                            uint32_t crop_h, uint32_t max_frames);
  uint32_t batch() const { return net_.batch(); }

  uint32_t max_frames() const { return max_frames_; }
  uint32_t frames() const { return uint32_t(times_.size()); }  // of the last forward
  uint32_t crop_w() const { return crop_w_; }
  uint32_t crop_h() const { return crop_h_; }
  const std::vector<uint32_t>& widths() const { return widths_; }
  nn::ConvStack& network() { return net_; }

  // He initialisation from `seed`, then the last layer's bias set to neutral_bias().
  void init(uint64_t seed);

  // Records frames at times[i] (F <= max_frames of them, inside view's window) over `crop` of view
  // `view`, with blurry: the view's blurry crop, 3 x crop_h x crop_w, linear.
  void forward(gpu::Commands& cmd, size_t view, const std::vector<double>& times, const Crop& crop,
               const gpu::Buffer& blurry);
  // After forward(): frame i (3 x crop_h x crop_w, linear), and E(t_i) at integral()[i pixels() ...].
  const gpu::Buffer& frame(uint32_t i) const { return frames_buf_.at(i); }
  const gpu::Buffer& integral() const { return integral_; }
  uint64_t pixels() const { return uint64_t(crop_w_) * crop_h_; }

  // Records the weight gradients (written, not added) of the last forward's calls, from
  // d(loss)/d(frame i) (3 x crop each, scaled by `scale`), or, with `target`, of the regression
  // scale * sum (log E(t_i) - log D_i)^2 to D (F x crop). Record after the forward, before the
  // next forward. An anchor adds its regression's gradient to the frames' (LdiAnchor).
  void backward_from_frames(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& frame_grads, float scale = 1.0f,
                            const LdiAnchor& anchor = {});
  void backward_from_target(gpu::Commands& cmd, const gpu::Buffer& target, float scale);

  void add_to(Adam& adam, float lr) { net_.add_to(adam, lr); }
  // Tensors "ldi.<i>.weight" and "ldi.<i>.bias"; load() checks the shapes (errors name `source`).
  void save(nn::SafetensorsFile& file) const { net_.save(file); }
  void load(const nn::SafetensorsFile& file, const std::string& source) { net_.load(file, source); }

 private:
  struct Call {
    uint32_t frame;
    Side side;
  };
  shaderio::LdiCombinePC combine_pc(uint32_t i, uint32_t mode, float scale, float anchor = 0) const;
  void combine(gpu::Commands& cmd, uint32_t i);
  void combine_bwd(gpu::Commands& cmd, uint32_t i, uint32_t mode, const gpu::Buffer& grads, float scale,
                   const LdiAnchor& anchor = {});
  void require_planes(const gpu::Buffer& b, uint32_t planes, const std::string& what) const;
  uint32_t chunk_size(uint32_t first) const;
  void run_chunk(gpu::Commands& cmd, uint32_t first);
  void backward_calls(gpu::Commands& cmd);
  double weight(uint32_t i, Side side) const;
  uint32_t call_of(uint32_t i, Side side) const;  // its plane of sides_, or kLdiNoSide

  gpu::Context& ctx_;
  const GpuEvents& events_;
  std::vector<uint32_t> widths_;
  uint32_t crop_w_, crop_h_, max_frames_;
  nn::ConvStack net_;
  gpu::Buffer sides_, side_grads_, integral_;  // sides: one plane per call
  std::vector<gpu::Buffer> frames_buf_;
  // The last forward's view, crop, times and blurry crop.
  size_t view_ = 0;
  Crop crop_;
  std::vector<double> times_;
  std::vector<Call> calls_;  // the sides of positive weight, frame by frame
  const gpu::Buffer* blurry_ = nullptr;
};

}  // namespace evflow::ldi
