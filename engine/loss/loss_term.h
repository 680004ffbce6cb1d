// LossTerm: the shape every training loss follows. A term records its forward and backward into
// the caller's Commands: the gradient w.r.t. its prediction, scaled by a weight, is written or
// added into a gradient buffer, and its scalar value is reduced on the GPU (fixed order, no
// atomics) into a small value buffer that the host reads after the submit with one small download.
//
// Two kinds plug into the trainer's registry:
//   ImageLossTerm     compares one predicted image with a target (L1, SSIM, blend): the blurry
//                     image model (mean of the virtual frames) against the blurry input.
//   ExposureLossTerm  sees every virtual frame of one exposure and adds a gradient per frame
//                     (the event loss; flow, LDI and residual terms follow the same shape).
#pragma once
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "gpu/buffer.h"
#include "gpu/commands.h"

namespace evflow {

class LossTerm {
 public:
  // `value_count` floats are written per record: the loss value first, then term-specific
  // components (documented by each term).
  LossTerm(gpu::Context& ctx, std::string name, float weight, uint32_t value_count);
  virtual ~LossTerm() = default;
  LossTerm(const LossTerm&) = delete;
  LossTerm& operator=(const LossTerm&) = delete;

  const std::string& name() const { return name_; }
  // A second instance of a term under its own name (a branch's copy of the image loss).
  void set_name(std::string name) { name_ = std::move(name); }
  float weight() const { return weight_; }
  void set_weight(float w) { weight_ = w; }

  // The unweighted loss value of the last submitted record (one 4-byte download).
  double value() const;
  // All value_count() floats of the last submitted record (one download).
  std::vector<float> values() const;
  uint32_t value_count() const { return value_count_; }

  // Where the values go: the term's own small buffer by default, or floats
  // [first, first + value_count()) of a shared buffer, so that a trainer reads every term's
  // value with a single download. The buffer must outlive the term's use of it.
  void set_value_slot(const gpu::Buffer& buffer, uint32_t first);
  const gpu::Buffer& value_buffer() const { return *value_buffer_; }
  uint32_t value_offset() const { return value_first_; }

 protected:
  gpu::Context& ctx_;

 private:
  std::string name_;
  float weight_;
  uint32_t value_count_;
  gpu::Buffer own_values_;
  const gpu::Buffer* value_buffer_;
  uint32_t value_first_ = 0;
};

class ImageLossTerm : public LossTerm {
 public:
  using LossTerm::LossTerm;
  // Records forward and backward: grad_out = (accumulate ? grad_out : 0) + weight * dL/dpred,
  // and the (unweighted) value L into the value slot. With accumulate = false grad_out is only
  // written, never read. pred, target and grad_out are the term's input layout (images: planar
  // float C x H x W).
  virtual void record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target,
                      const gpu::Buffer& grad_out, float weight, bool accumulate) = 0;
  // The same with the term's own weight().
  void record(gpu::Commands& cmd, const gpu::Buffer& pred, const gpu::Buffer& target, const gpu::Buffer& grad_out,
              bool accumulate) {
    record(cmd, pred, target, grad_out, weight(), accumulate);
  }
};

// One exposure of a training step, as an exposure-level term sees it: 2N+1 virtual frames at
// times u in [0, 1] over [t0, t1] (the events' clock), each frame's planar RGB render (linear
// light) and the buffer its gradient is added into.
struct ExposureFrames {
  uint32_t view = 0;
  uint32_t width = 0, height = 0;
  double t0 = 0, t1 = 0;
  std::vector<double> u;
  std::vector<const gpu::Buffer*> rgb;
  std::vector<const gpu::Buffer*> grad;
  uint64_t seed = 0;  // the step's random stream (terms that sample, e.g. the event loss's t_s)
  // Optional gradient plumbing, for terms that fold it (ExposureLossTerm::folds); LossTerms hands
  // each part only to the term it concerns. grad_in: what frame i's gradient starts from instead
  // of grad[i]'s contents (the image terms' share), for the first term. render_grad: where the
  // last term writes d(loss)/d(render i) of the frames' sRGB renders (rgb[i] = decode(render i)),
  // its frame gradient times decode'(render i), instead of writing grad[i].
  std::vector<const gpu::Buffer*> grad_in, render_grad;
  double time_at(size_t i) const { return t0 + u[i] * (t1 - t0); }
};

class ExposureLossTerm : public LossTerm {
 public:
  using LossTerm::LossTerm;
  // Records forward and backward: grad[i] += weight * dL/d rgb[i] for every frame (or, where the
  // term folds and the frames ask, grad[i] = grad_in[i] + ..., render_grad[i] = grad[i] *
  // decode'(render[i])), and the unweighted value L into the value slot.
  virtual void record(gpu::Commands& cmd, const ExposureFrames& frames, float weight) = 0;
  void record(gpu::Commands& cmd, const ExposureFrames& frames) { record(cmd, frames, weight()); }
  // Whether record() honours grad_in and render_grad for these frames; without it the
  // term only adds into grad.
  virtual bool folds(const ExposureFrames&) const { return false; }
};

}  // namespace evflow
