// The learnable double integral as a training branch (paper Sec. 4.5; docs/ldi.md): its own
// network (engine/ldi), its own Adam, its loss terms, beside the splats. Per step, over a crop of
// the step's view (random with ldi_crop > 0, else the whole image):
//
//   LDI frames C_ldi(t_i) = B / E(t_i) at the 2N+1 virtual frames' times (linear light)
//   L_blur^ldi  the frames' mean against the blurry input (the trainer's image loss, loss_space)
//   L_ev^ldi    the event loss on the LDI frames, on from the first step at a constant weight
//   L_joint     (1/(2N+1)) sum_i L(C_ldi(t_i), C_gs(t_i)) in loss_space, into the renders and
//               (joint_ldi_share of it) the LDI frames, on from joint_from; weighted by
//               joint_weight times the crop's share of the view (per render pixel the weight
//               of the paper's L_joint over whole images)
//   anchor      ldi_anchor_weight * the mean over the crop and frames of (log E(t_i) - log D(t_i))^2,
//               D EDI's double integral with the dataset's thresholds (the pre-fit's regression,
//               kept as a prior: the network may move from EDI where its terms say so, not drift)
//
// record() runs in the trainer's loss stage (after the image model's forward); backward() after
// the image model's render gradients: it adds the joint loss's gradients into the renders' and
// steps the network.
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "events/edi.h"
#include "events/gpu_events.h"
#include "io/dataset.h"
#include "ldi/crop_events.h"
#include "ldi/full_view.h"
#include "ldi/joint_loss.h"
#include "ldi/ldi_model.h"
#include "loss/event_loss.h"
#include "loss/image_losses.h"
#include "nn/safetensors.h"
#include "optim/adam.h"
#include "train/image_model.h"
#include "train/train_config.h"

namespace evflow {

class LdiBranch {
 public:
  // frame_u: the virtual frames' times u in [0, 1]. state: saved weights and Adam state
  // (state(); errors name `source`); without it the network is initialised and pre-fitted to
  // EDI (ldi_init_steps).
  LdiBranch(gpu::Context& ctx, const io::Dataset& data, const TrainConfig& cfg, const std::vector<double>& frame_u,
            const nn::SafetensorsFile* state, const std::string& source = "ldi.safetensors");

  // The terms, for the trainer's list: (term, counted with the event schedule): none is.
  std::vector<std::pair<LossTerm*, bool>> terms();
  // Records the LDI frames and the three terms for view `view` with the step's renders (sRGB)
  // and the image model (its linear frames). joint_on: L_joint is on this step (else its value
  // reads 0 and it sends no gradient); seed: the step's random stream.
  void record(gpu::Commands& cmd, uint32_t view, uint32_t step, const std::vector<const gpu::Buffer*>& renders,
              const ImageModel& image_model, bool joint_on, uint64_t seed);
  // Adds the joint loss's gradients into image_model.render_grad(i), and records the network's
  // backward and Adam step.
  void backward(gpu::Commands& cmd, const ImageModel& image_model);

  // Weights ("ldi.<i>.weight", "ldi.<i>.bias"), the Adam moments ("adam.<group>.exp_avg",
  // "adam.<group>.exp_avg_sq") and the Adam step count (metadata "adam_step").
  nn::SafetensorsFile state() const;
  ldi::LdiModel& model() { return *model_; }
  // The LDI frames at the virtual frames' times over the whole of view `view` with the current
  // weights (for display: a tile-sized second model, made at the first call, runs them; the
  // training model and its crop are untouched). Records and submits on `cmd`; per frame planar
  // linear RGB, 3 x H x W. `only`: the virtual frames to compute, in the order given (empty: all).
  std::vector<std::vector<float>> view_frames(gpu::Commands& cmd, uint32_t view,
                                              const std::vector<uint32_t>& only = {});
  // The frames' times of view `view`: t_0 + u (t_2N - t_0) for each virtual frame's u.
  std::vector<double> frame_times(uint32_t view) const;
  const ldi::Crop& crop() const { return crop_; }  // of the last record

 private:
  void initialise();
  void load_state(const nn::SafetensorsFile& state, const std::string& source);
  ldi::Crop choose_crop(uint32_t step) const;
  void record_blur(gpu::Commands& cmd);
  void record_joint(gpu::Commands& cmd, const std::vector<const gpu::Buffer*>& renders, const ImageModel& im);
  void record_events(gpu::Commands& cmd, uint32_t view, uint64_t seed);
  void colour(gpu::Commands& cmd, uint32_t op, const gpu::Buffer& x, const gpu::Buffer& g, const gpu::Buffer& y);
  void make_anchor_targets();
  events::EdiThresholds edi_thresholds() const;

  gpu::Context& ctx_;
  const io::Dataset& data_;
  const TrainConfig& cfg_;
  std::vector<double> frame_u_;
  bool srgb_;
  std::unique_ptr<GpuEvents> events_;
  std::unique_ptr<ldi::LdiModel> model_;
  std::unique_ptr<ldi::CropEvents> crop_events_;
  std::unique_ptr<BlendLoss> blur_;
  std::unique_ptr<EventLoss> event_;
  std::unique_ptr<ldi::JointLoss> joint_;
  std::unique_ptr<Adam> adam_;
  std::unique_ptr<ldi::FullViewFrames> full_view_;  // view_frames(), made at its first call
  std::vector<gpu::Buffer> blurry_, target_;        // per view: linear, and in loss_space
  std::vector<gpu::Buffer> anchor_;                 // per view: EDI's D at the frames' times, F x H x W
  gpu::Buffer anchor_crop_;                         // F x crop
  ldi::Crop crop_;
  uint32_t view_ = 0;
  bool joint_on_ = false;
  uint64_t values_;  // 3 x crop pixels
  gpu::Buffer blurry_crop_, target_crop_, mean_, mean_ls_, v_mean_ls_, v_mean_, tmp_;
  // Per frame: gradient of the LDI frame (linear), the frames in loss space, the joint's
  // gradients of both sides in loss space, the render gradient of the crop.
  std::vector<gpu::Buffer> grad_, ldi_ls_, gs_ls_, g_ldi_ls_, g_gs_ls_, g_render_;
};

}  // namespace evflow
