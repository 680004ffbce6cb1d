// The backward of an exposure's frames with one projection backward for all of them
// (splat/project_bwd_frames_block): each Gaussian's parameters read once, its gradients summed
// over the frames in registers and stored once, every frame's pose partials in one buffer and one
// pose reduction. The values are those of one projection backward per frame in frame order.
#include <algorithm>

#include "splat/rasterizer.h"
#include "splat/splat_layout.h"

namespace evflow {

using namespace shaderio;

static_assert(sizeof(CameraPC) == 16 * kProjectFrameTexels, "a frame's camera is kProjectFrameTexels texels");
static_assert(sizeof(ProjectFramesPC) <= 128, "push constants above 128 bytes");

// Each frame's first slot in the gradient planes: its slots start at an offset every plane may
// be bound at (the float plane's 4 bytes a slot, the vec4 planes' 16). Empty where the batch
// cannot run in one pass: not the CPU kernels, one frame or more than kProjectFramesMax, renders
// of different settings, or planes past what one binding or texel view holds.
std::vector<uint64_t> Rasterizer::frame_slot_bases(const std::vector<const RenderState*>& states) const {
  const auto& caps = ctx_.caps();
  const size_t frames = states.size();
  if (block_suffix_.empty() || frames < 2 || frames > kProjectFramesMax || states[0]->count_ == 0) return {};
  if (!caps.fits_bindings(10, 11)) return {};
  const uint64_t step = std::max<uint64_t>(caps.min_storage_offset_alignment, 16) / 4;
  std::vector<uint64_t> bases;
  uint64_t total = 0;
  for (const RenderState* st : states) {
    if (st->project_pc_.sh_degree != states[0]->project_pc_.sh_degree ||
        st->project_pc_.flags != states[0]->project_pc_.flags)
      return {};
    bases.push_back(total);
    total += (std::max<uint64_t>(st->num_isects_, 1) + step - 1) / step * step;
  }
  const uint64_t n = states[0]->count_;
  const uint64_t most_texels = std::max({total, frames * (n + 1), frames * 3 * n});
  if (total * 16 > caps.max_storage_buffer_range || most_texels > caps.max_texel_buffer_elements ||
      frames * 3 * n * 16 > caps.max_allocation_size)
    return {};
  bases.push_back(total);  // one past the last frame's slots
  return bases;
}

// The compositing backward of each frame into its slots, then every frame's projection backward
// in one pass (the first frame's gradients overwrite, as record_backward's do) and one reduction
// of the frames' pose partials into poses_ (slot i: frame i).
void Rasterizer::record_backward_frames(const std::vector<const RenderState*>& states,
                                        const std::vector<uint64_t>& bases, const GaussianBuffers& params,
                                        const std::vector<const gpu::Buffer*>& v_rgb, const gpu::Buffer& v_alpha,
                                        GaussianBuffers& grads) {
  const size_t frames = states.size(), n = params.count;
  ensure_backward_buffers(n, bases.back());
  const uint32_t partials = pose_partials(n);
  pose_partial_.ensure(uint64_t(frames) * partials * 24);
  for (size_t f = 0; f < frames; ++f) record_composite_backward(*states[f], *v_rgb[f], v_alpha, bases[f]);

  const ProjectPC& first = states[0]->project_pc_;
  ProjectFramesPC pc{};
  pc.num_gaussians = uint32_t(n);
  pc.frames = uint32_t(frames);
  pc.sh_degree = first.sh_degree;
  pc.flags = first.flags & ~kFlagAccumulate;
  pc.partials = partials;
  std::vector<CameraPC> cams;
  const bool view_dependent = first.sh_degree >= 1;
  frame_offsets_.ensure(frames * (n + 1) * 4);
  frame_color_.ensure(frames * n * 16);
  if (view_dependent) frame_dcolor_.ensure(frames * n * 48);
  for (size_t f = 0; f < frames; ++f) {
    const RenderState& st = *states[f];
    pc.slot_base[f] = uint32_t(bases[f]);
    cams.push_back(st.project_pc_.cam);
    cmd_.copy(st.isect_offset_, frame_offsets_, (n + 1) * 4, 0, f * (n + 1) * 4);
    cmd_.copy(st.proj_color_, frame_color_, n * 16, 0, f * n * 16);
    if (view_dependent) cmd_.copy(st.proj_dcolor_, frame_dcolor_, n * 48, 0, f * n * 48);
  }
  frame_cams_.ensure(frames * sizeof(CameraPC));
  frame_cams_.write(cams);
  // The bands above the active degree get zeros, as an overwrite's do (record_backward).
  for (int l = int(pc.sh_degree) + 1; l <= grads.sh_degree; ++l) cmd_.fill(grads.sh[l], 0u);
  auto band = [&](int l) -> const gpu::Buffer& { return l <= grads.sh_degree ? grads.sh[l] : grads.sh[0]; };
  const std::vector<gpu::Bind> binds = {{kParamBindMeans, params.means},
                                        {kParamBindLogScales, params.log_scales},
                                        {kParamBindQuats, params.quats},
                                        {kParamBindOpacities, params.opacity_logits},
                                        {kProjectBwdBindOffsets, frame_offsets_},
                                        {kProjectBwdBindG0, isect_grad_[0]},
                                        {kProjectBwdBindG1, isect_grad_[1]},
                                        {kProjectBwdBindG2, isect_grad_[2]},
                                        {kProjectBwdBindVMeans, grads.means},
                                        {kProjectBwdBindVLogScales, grads.log_scales},
                                        {kProjectBwdBindVQuats, grads.quats},
                                        {kProjectBwdBindVOpacities, grads.opacity_logits},
                                        {kProjectBwdBindVSh0, band(0)},
                                        {kProjectBwdBindVSh1, band(1)},
                                        {kProjectBwdBindVSh2, band(2)},
                                        {kProjectBwdBindVSh3, band(3)},
                                        {kProjectBwdBindGrad2d, grad2d_norm_},
                                        {kProjectBwdBindPosePartial, pose_partial_},
                                        {kProjectBwdBindProjC, frame_color_},
                                        {kProjectBwdBindDColor, view_dependent ? frame_dcolor_ : frame_color_},
                                        {kProjectBwdBindFrames, frame_cams_}};
  cmd_.dispatch("splat/project_bwd_frames_block", binds, pc,
                cmd_.linear_groups(gpu::Commands::div_up(n, kProjectGroupSize)));
  ReducePC rp{partials, 0, 0, 0};
  cmd_.dispatch("splat/pose_reduce", {{kPoseReduceBindPartials, pose_partial_}, {kPoseReduceBindPose, poses_}}, rp,
                gpu::Groups{uint32_t(frames), 1, 1});
  cmd_.mark("project backward");
}

}  // namespace evflow
