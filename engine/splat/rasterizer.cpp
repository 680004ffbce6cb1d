#include "splat/rasterizer.h"

#include <algorithm>
#include <cstring>

#include "splat/camera_pc.h"
#include "splat/splat_layout.h"

namespace evflow {

using namespace shaderio;

static constexpr uint32_t kBandCoeffs[4] = {1, 3, 5, 7};

static gpu::Buffer make(gpu::Context& ctx, uint64_t bytes, const std::string& name) {
  return gpu::Buffer(ctx, bytes, name);
}

// `n`, or an error naming the largest count the device holds, before any buffer is allocated.
static size_t checked_count(const gpu::Context& ctx, size_t n, int degree) {
  if (n > GaussianBuffers::max_count(ctx, degree))
    throw gpu::Error(std::to_string(n) + " Gaussians at SH degree " + std::to_string(degree) + " do not fit " +
                     ctx.caps().name + "'s storage binding limit of " +
                     std::to_string(ctx.caps().max_storage_buffer_range) + " bytes; the largest supported count is " +
                     std::to_string(GaussianBuffers::max_count(ctx, degree)));
  return n;
}

GaussianBuffers::GaussianBuffers(gpu::Context& ctx, size_t n, int degree, const std::string& prefix)
    : count(checked_count(ctx, n, degree)),
      sh_degree(degree),
      means(make(ctx, n * 12, prefix + "means")),
      log_scales(make(ctx, n * 12, prefix + "log_scales")),
      quats(make(ctx, n * 16, prefix + "quats")),
      opacity_logits(make(ctx, n * 4, prefix + "opacity_logits")),
      sh{make(ctx, n * 12, prefix + "sh0"), make(ctx, degree >= 1 ? n * 36 : 16, prefix + "sh1"),
         make(ctx, degree >= 2 ? n * 60 : 16, prefix + "sh2"), make(ctx, degree >= 3 ? n * 84 : 16, prefix + "sh3")} {}

size_t GaussianBuffers::max_count(const gpu::Context& ctx, int degree) {
  // The widest per-Gaussian buffer: the degree-3 band (84 B), the degree-2 band (60 B), else the
  // rasterizer's d(colour)/d(direction) at SH degree >= 1 (three vec4s, 48 B: wider than the
  // degree-1 band's 36 B), else quats or the projection/intersection state (16 B per Gaussian).
  // Buffers are whole vec4s (Buffer rounds up; project reads the SH bands as vec4s): the count
  // whose widest buffer, rounded up, still fits.
  uint64_t widest = degree >= 3 ? 84 : degree >= 2 ? 60 : degree >= 1 ? 48 : 16;
  return static_cast<size_t>((ctx.caps().max_storage_buffer_range & ~uint64_t(15)) / widest);
}

void GaussianBuffers::upload(const GaussianCloud& c) {
  if (c.size() != count || c.sh_degree != sh_degree)
    throw gpu::Error("GaussianBuffers::upload: cloud of " + std::to_string(c.size()) + " at degree " +
                     std::to_string(c.sh_degree) + " into buffers for " + std::to_string(count) + " at degree " +
                     std::to_string(sh_degree));
  if (!count) return;
  means.write(c.means);
  log_scales.write(c.log_scales);
  quats.write(c.quats);
  opacity_logits.write(c.opacity_logits);
  const int K = c.coeffs();
  for (int l = 0; l <= sh_degree; ++l) {
    const uint32_t first = l * l, nb = kBandCoeffs[l];
    std::vector<float> band(count * nb * 3);
    for (size_t g = 0; g < count; ++g)
      std::memcpy(&band[g * nb * 3], &c.sh[(g * K + first) * 3], nb * 3 * sizeof(float));
    sh[l].write(band);
  }
}

GaussianCloud GaussianBuffers::download() const {
  GaussianCloud c;
  c.resize(count, sh_degree);
  if (!count) return c;
  c.means = means.read<float>(count * 3);
  c.log_scales = log_scales.read<float>(count * 3);
  c.quats = quats.read<float>(count * 4);
  c.opacity_logits = opacity_logits.read<float>(count);
  const int K = c.coeffs();
  for (int l = 0; l <= sh_degree; ++l) {
    const uint32_t first = l * l, nb = kBandCoeffs[l];
    auto band = sh[l].read<float>(count * nb * 3);
    for (size_t g = 0; g < count; ++g)
      std::memcpy(&c.sh[(g * K + first) * 3], &band[g * nb * 3], nb * 3 * sizeof(float));
  }
  return c;
}

RenderState::RenderState(gpu::Context& ctx)
    : proj_mean_conic_(ctx, 16, "proj_mean_conic"),
      proj_misc_(ctx, 16, "proj_misc"),
      proj_color_(ctx, 16, "proj_color"),
      proj_dcolor_(ctx, 16, "proj_dcolor"),
      tile_rect_(ctx, 16, "tile_rect"),
      tiles_touched_(ctx, 16, "tiles_touched"),
      isect_offset_(ctx, 16, "isect_offset"),
      keys_(ctx, 16, "keys"),
      slot_from_isect_(ctx, 16, "slot_from_isect"),
      keys_alt_(ctx, 16, "keys_alt"),
      slots_alt_(ctx, 16, "slots_alt"),
      gaussian_id_from_slot_(ctx, 16, "gaussian_id_from_slot"),
      block_words_(ctx, 16, "block_words"),
      tile_range_(ctx, 16, "tile_range"),
      final_T_(ctx, 16, "final_T"),
      last_isect_(ctx, 16, "last_isect"),
      out_{gpu::Buffer(ctx, 16, "out_rgb"), gpu::Buffer(ctx, 16, "out_alpha"), gpu::Buffer(ctx, 16, "out_depth")} {}

RasterKernels RasterKernels::for_context(const gpu::Context& ctx) {
  const bool cpu = ctx.caps().cpu_driver;
  const gpu::ContextOptions& o = ctx.options();
  RasterKernels k;
  // Compositing kernels: one pixel per invocation (GPUs) or a block of pixels per invocation
  // (CPU drivers, where every shared-memory access is a loop over the SIMD lanes).
  k.block = o.raster_kernel.empty() ? cpu : o.raster_kernel == "block";
  // Cross-lane operations are emulated on CPU drivers, slower there than per-lane shared-memory
  // adds (docs/rasterizer.md); GPUs reduce in the subgroup first.
  k.subgroup_reduce = o.subgroup_reduce < 0 ? !cpu : o.subgroup_reduce == 1;
  return k;
}

Rasterizer::Rasterizer(gpu::Context& ctx) : Rasterizer(ctx, RasterKernels::for_context(ctx)) {}

Rasterizer::Rasterizer(gpu::Context& ctx, const RasterKernels& kernels)
    : ctx_(ctx),
      cmd_(ctx),
      scan_(ctx),
      sort_(ctx),
      grad2d_norm_(ctx, 16, "grad2d_norm"),
      pose_partial_(ctx, 16, "pose_partial"),
      poses_(ctx, 32, "pose_gradients"),
      counts_(ctx, 16, "isect_counts"),
      subgroup_reduce_(kernels.subgroup_reduce),
      block_suffix_(kernels.block ? "_block" : "") {
  for (const char* q : {"mean_conic_xy", "conic_z_opacity_rg", "blue"})
    isect_grad_.emplace_back(ctx, 16, std::string("isect_grad_") + q);
}

// SH band l of a set of buffers, or band 0 standing in for a band above its degree (the
// shaders never read it, but every binding needs a buffer).
static const gpu::Buffer& sh_band(const GaussianBuffers& b, int l) { return l <= b.sh_degree ? b.sh[l] : b.sh[0]; }

static uint32_t bit_width(uint32_t v) {
  uint32_t b = 0;
  while (v) {
    ++b;
    v >>= 1;
  }
  return b;
}

void Rasterizer::set_pc(const GaussianBuffers& params, const Camera& cam, const RenderSettings& s,
                        RenderState& st) const {
  if (cam.width == 0 || cam.height == 0) throw gpu::Error("render: camera has zero size");
  st.width_ = cam.width;
  st.height_ = cam.height;
  st.depth_ = s.depth;
  const uint32_t tiles_x = (st.width_ + kTileSize - 1) / kTileSize, tiles_y = (st.height_ + kTileSize - 1) / kTileSize;
  const uint32_t tile_bits = bit_width(tiles_x * tiles_y);  // 2^tile_bits > number of tiles
  // 16 bits a tile coordinate (tile_rect_pack in splat_math.glsl).
  if (tile_bits > 24 || tiles_x > 0xFFFF || tiles_y > 0xFFFF)
    throw gpu::Error("render: image of " + std::to_string(st.width_) + "x" + std::to_string(st.height_) +
                     " has too many tiles");
  // Keys of whole 8-bit digits (the sort's passes), with at least kDepthKeyBitsMin depth bits
  // where 32 bits leave room: 3 passes up to 512 tiles (346x260: 374). Equal keys are put in
  // depth order after the sort, so fewer depth bits cost time, not exactness.
  const uint32_t depth_bits = std::min({23u, 32u - tile_bits, (tile_bits + kDepthKeyBitsMin + 7) / 8 * 8 - tile_bits});
  st.sort_bits_ = tile_bits + depth_bits;
  const int degree = s.sh_degree < 0 ? params.sh_degree : std::min(s.sh_degree, params.sh_degree);

  ProjectPC& pp = st.project_pc_;
  pp = ProjectPC{};
  pp.cam = camera_pc(cam);
  pp.num_gaussians = static_cast<uint32_t>(params.count);
  pp.sh_degree = static_cast<uint32_t>(degree);
  pp.flags = (s.antialiased ? kFlagAntialiased : 0u) | (uint32_t(params.sh_degree) << 8);
  pp.tiles_x = tiles_x;
  pp.tiles_y = tiles_y;
  pp.depth_bits = depth_bits;
  pp.num_isects = 0;
  pp.sentinel_key = st.sort_bits_ >= 32 ? 0xFFFFFFFFu : ((1u << st.sort_bits_) - 1u);
  static_assert(sizeof(ProjectPC) <= 128 && sizeof(RasterPC) <= 128);

  RasterPC& rp = st.raster_pc_;
  rp = RasterPC{};
  rp.background = glm::vec4(s.background[0], s.background[1], s.background[2], 0.0f);
  rp.width = st.width_;
  rp.height = st.height_;
  rp.tiles_x = tiles_x;
  rp.tiles_y = tiles_y;
  rp.depth_bits = depth_bits;
  rp.subgroup_reduce = subgroup_reduce_ ? 1u : 0u;
}

// The per-Gaussian and per-pixel buffers of a render.
void Rasterizer::ensure_forward_buffers(RenderState& st) const {
  const size_t n = st.count_;
  const uint64_t pixels = uint64_t(st.width_) * st.height_;
  st.proj_mean_conic_.ensure(n * 16);
  st.proj_misc_.ensure(n * 16);
  st.proj_color_.ensure(n * 16);
  // d(colour)/d(direction) for project_bwd: only with view-dependent colour (SH degree >= 1); its
  // three vec4s (48 B) per Gaussian are counted in GaussianBuffers::max_count.
  if (st.project_pc_.sh_degree >= 1) st.proj_dcolor_.ensure(n * 48);
  st.tile_rect_.ensure(n * 16);
  st.tiles_touched_.ensure(n * 4);
  st.isect_offset_.ensure((n + 1) * 4);
  st.tile_range_.ensure(uint64_t(st.raster_pc_.tiles_x) * st.raster_pc_.tiles_y * 8);
  st.out_.rgb.ensure(pixels * 12);
  st.out_.alpha.ensure(pixels * 4);
  st.out_.depth.ensure(pixels * 4);
  // Whole tiles: the block kernels keep these two planes tile by tile (splat_layout.h).
  const uint64_t tile_pixels = uint64_t(st.raster_pc_.tiles_x) * st.raster_pc_.tiles_y * kTileSize * kTileSize;
  st.final_T_.ensure(tile_pixels * 4);
  st.last_isect_.ensure(tile_pixels * 4);
}

RenderState Rasterizer::forward(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings) {
  RenderState st(ctx_);
  forward(params, cam, settings, st);
  return st;
}

// The projection and the prefix sum of the tiles each Gaussian touches.
void Rasterizer::record_project(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings,
                                RenderState& st) {
  set_pc(params, cam, settings, st);
  st.count_ = params.count;
  const size_t n = params.count;
  ensure_forward_buffers(st);
  const ProjectPC& pp = st.project_pc_;
  cmd_.dispatch("splat/project",
                {{kParamBindMeans, params.means},
                 {kParamBindLogScales, params.log_scales},
                 {kParamBindQuats, params.quats},
                 {kParamBindOpacities, params.opacity_logits},
                 {kParamBindSh0, sh_band(params, 0)},
                 {kParamBindSh1, sh_band(params, 1)},
                 {kParamBindSh2, sh_band(params, 2)},
                 {kParamBindSh3, sh_band(params, 3)},
                 {kProjectBindProjA, st.proj_mean_conic_},
                 {kProjectBindProjB, st.proj_misc_},
                 {kProjectBindProjC, st.proj_color_},
                 {kProjectBindRect, st.tile_rect_},
                 {kProjectBindCount, st.tiles_touched_},
                 {kProjectBindDColor, st.proj_dcolor_}},
                pp, cmd_.linear_groups(gpu::Commands::div_up(n, kProjectGroupSize)));
  cmd_.mark("project");
  scan_.record(cmd_, st.tiles_touched_, st.isect_offset_, uint32_t(n), uint32_t(n + 1));
  cmd_.mark("scan");
}

// The intersection count the prefix sum left (read back) sizes the intersection buffers.
void Rasterizer::set_count(RenderState& st, uint32_t isects) const {
  const uint32_t m = st.num_isects_ = isects;
  st.project_pc_.num_isects = m;
  st.raster_pc_.num_isects = m;

  const uint64_t max_range = ctx_.caps().max_storage_buffer_range;
  if (uint64_t(m) * 4 > max_range)
    throw gpu::Error(std::to_string(m) + " tile intersections exceed the storage binding limit of " + ctx_.caps().name +
                     " (" + std::to_string(max_range / 4) + " at most)");
  // The block kernels read the sorted slots as a texel buffer, one texel per intersection.
  const uint64_t max_texels = ctx_.caps().max_texel_buffer_elements;
  if (!block_suffix_.empty() && m > max_texels)
    throw gpu::Error(std::to_string(m) + " tile intersections exceed the texel buffer limit of " + ctx_.caps().name +
                     " (" + std::to_string(max_texels) + " at most)");
}

// Emit, sort, tile ranges and compositing.
void Rasterizer::record_raster(RenderState& st) {
  const size_t n = st.count_;
  const uint32_t m = st.num_isects_;
  const ProjectPC& pp = st.project_pc_;
  st.keys_.ensure(uint64_t(m) * 4);
  st.gaussian_id_from_slot_.ensure(uint64_t(m) * 4);
  if (m) {
    cmd_.dispatch("splat/emit" + block_suffix_,
                  {{kEmitBindProjA, st.proj_mean_conic_},
                   {kEmitBindProjB, st.proj_misc_},
                   {kEmitBindRect, st.tile_rect_},
                   {kEmitBindOffsets, st.isect_offset_},
                   {kEmitBindKeys, st.keys_},
                   {kEmitBindGid, st.gaussian_id_from_slot_}},
                  pp, cmd_.linear_groups(gpu::Commands::div_up(n, kProjectGroupSize)));
  }
  cmd_.mark("emit");
  auto [sorted_keys, sorted_slots] =
      sort_.record_order(cmd_, st.keys_, st.slot_from_isect_, st.keys_alt_, st.slots_alt_, m, st.sort_bits_);
  st.sorted_in_alt_ = sorted_slots == &st.slots_alt_;
  if (m > 1) {
    std::vector<gpu::Bind> runs = {{kDepthRunsBindKeys, *sorted_keys},
                                   {kDepthRunsBindSlots, st.sorted_slots()},
                                   {kDepthRunsBindGid, st.gaussian_id_from_slot_},
                                   {kDepthRunsBindProjB, st.proj_misc_}};
    if (!block_suffix_.empty()) runs.push_back({kDepthRunsBindSlotsIn, st.sorted_slots()});
    cmd_.dispatch("splat/depth_runs" + block_suffix_, runs, st.raster_pc_,
                  cmd_.linear_groups(gpu::Commands::div_up(m, kDepthRunsGroupSize * kDepthRunsSpan)));
  }
  cmd_.mark("sort");
  // The block forward finds each tile's range itself, in the sorted keys.
  if (block_suffix_.empty()) {
    cmd_.fill(st.tile_range_, 0);
    cmd_.dispatch("splat/tile_ranges", {{kTileRangesBindKeys, *sorted_keys}, {kTileRangesBindRanges, st.tile_range_}},
                  st.raster_pc_, cmd_.linear_groups(gpu::Commands::div_up(m, kIsectGroupSize)));
  }
  std::vector<gpu::Bind> bindings = {
      {kRasterBindRanges, st.tile_range_},         {kRasterBindSlots, st.sorted_slots()},
      {kRasterBindGid, st.gaussian_id_from_slot_}, {kRasterBindProjA, st.proj_mean_conic_},
      {kRasterBindProjB, st.proj_misc_},           {kRasterBindProjC, st.proj_color_},
      {kRasterizeBindOutRgb, st.out_.rgb},         {kRasterizeBindOutAlpha, st.out_.alpha},
      {kRasterizeBindOutT, st.final_T_},           {kRasterizeBindOutLast, st.last_isect_}};
  // The block forward's "_nodepth" build has no depth plane.
  const bool depth_free = !st.depth_ && !block_suffix_.empty();
  if (!depth_free) bindings.push_back({kRasterizeBindOutDepth, st.out_.depth});
  if (!block_suffix_.empty()) {
    const uint64_t tiles = uint64_t(st.raster_pc_.tiles_x) * st.raster_pc_.tiles_y;
    st.block_words_.ensure((uint64_t(m) / 32 + tiles + 1) * kForwardBlocks * 4);
    bindings.push_back({kRasterizeBindOutBlocks, st.block_words_});
    bindings.push_back({kRasterizeBindSortedKeys, *sorted_keys});
  }
  cmd_.dispatch("splat/rasterize" + block_suffix_ + (depth_free ? "_nodepth" : ""), bindings, st.raster_pc_,
                cmd_.linear_groups(st.raster_pc_.tiles_x * st.raster_pc_.tiles_y));
  cmd_.mark("rasterize");
}

void Rasterizer::forward(const GaussianBuffers& params, const Camera& cam, const RenderSettings& settings,
                         RenderState& st) {
  forward(params, {cam}, settings, {&st});
}

void Rasterizer::forward(const GaussianBuffers& params, const std::vector<Camera>& cams, const RenderSettings& settings,
                         const std::vector<RenderState*>& states) {
  if (cams.size() != states.size()) throw gpu::Error("Rasterizer::forward: one state per camera expected");
  // Each render's count is gathered into counts_, so that one download reads them all.
  counts_.ensure(cams.size() * 4);
  for (size_t i = 0; i < cams.size(); ++i) {
    record_project(params, cams[i], settings, *states[i]);
    if (params.count) cmd_.copy(states[i]->isect_offset_, counts_, 4, uint64_t(params.count) * 4, i * 4);
  }
  cmd_.submit();
  stage_ms_ = cmd_.stage_ms();
  const std::vector<uint32_t> counts =
      params.count ? counts_.read<uint32_t>(cams.size()) : std::vector<uint32_t>(cams.size(), 0);
  for (size_t i = 0; i < states.size(); ++i) {
    set_count(*states[i], counts[i]);
    sort_.reserve(states[i]->num_isects_);  // the sort's scratch at its largest before any is recorded
  }
  for (RenderState* st : states) record_raster(*st);
  cmd_.submit();
  for (auto& s : cmd_.stage_ms()) stage_ms_.push_back(s);
}

// A backward's inputs against its render.
void Rasterizer::check_backward(const RenderState& st, const GaussianBuffers& params, const gpu::Buffer& v_rgb,
                                const gpu::Buffer& v_alpha, const GaussianBuffers& grads) const {
  if (params.count != st.count_) throw gpu::Error("Rasterizer::backward: parameters differ from the render's");
  if (grads.count != params.count || grads.sh_degree != params.sh_degree)
    throw gpu::Error("Rasterizer::backward: gradient buffers do not match the parameters");
  const uint64_t pixels = uint64_t(st.width_) * st.height_;
  if (v_rgb.size() < pixels * 12 || v_alpha.size() < pixels * 4)
    throw gpu::Error("Rasterizer::backward: v_rgb / v_alpha are smaller than the image");
}

// Bytes of per-intersection gradient plane k for `isects` intersections: two vec4 planes and a
// float plane (splat_layout.h).
// The third plane is a whole number of vec4s: the "_block" project_bwd reads it four slots to a texel.
static uint64_t isect_grad_bytes(size_t k, uint64_t isects) {
  const uint64_t n = std::max<uint64_t>(isects, 1);
  return k < 2 ? n * 16 : (n + 3) / 4 * 16;
}

// The backward's scratch for renders of `n` Gaussians with up to `isects` intersections.
void Rasterizer::ensure_backward_buffers(size_t n, uint64_t isects) {
  const uint64_t max_range = ctx_.caps().max_storage_buffer_range;
  if (isects * 16 > max_range)  // the two vec4 gradient planes: the widest per-intersection buffers
    throw gpu::Error(std::to_string(isects) +
                     " tile intersections exceed, in the backward pass, the storage binding limit of " +
                     ctx_.caps().name + " (" + std::to_string(max_range / 16) + " at most)");
  for (size_t k = 0; k < isect_grad_.size(); ++k) isect_grad_[k].ensure(isect_grad_bytes(k, isects));
  grad2d_norm_.ensure(n * 4);
  pose_partial_.ensure(uint64_t(std::max<uint32_t>(pose_partials(n), 1)) * 24);
}

// project_bwd's pose partials for n Gaussians: one per workgroup, or in the "_block" builds one
// per subgroup (project_bwd.comp).
uint32_t Rasterizer::pose_partials(size_t n) const {
  const uint32_t groups = gpu::Commands::div_up(n, kProjectGroupSize);
  if (block_suffix_.empty()) return groups;
  return groups * gpu::Commands::div_up(kProjectGroupSize, std::max(ctx_.caps().subgroup_size, 1u));
}

// The block backward's build: with subgroup barriers where its workgroup is one subgroup (16
// invocations in subgroups of 16 lanes or more; blocks of 4 x 8 pixels, 8 invocations, in
// subgroups of 8), else with workgroup barriers (rasterize_bwd_block.comp says why).
std::string Rasterizer::block_bwd_suffix() const {
  if (block_suffix_.empty()) return "";
  const uint32_t lanes = ctx_.caps().subgroup_size;
  return lanes >= 16 ? "_sg" : lanes == 8 ? "_sg8" : "";
}

// The compositing's backward and the projection's, for one render.
void Rasterizer::record_backward(const RenderState& st, const GaussianBuffers& params, const gpu::Buffer& v_rgb,
                                 const gpu::Buffer& v_alpha, GaussianBuffers& grads, bool accumulate,
                                 uint32_t pose_slot) {
  const uint32_t groups = gpu::Commands::div_up(params.count, kProjectGroupSize);
  auto plane = [&](int k) { return gpu::BufferRef(isect_grad_[k]); };
  // The block kernel adds no floats in shared memory; the per-pixel one needs the
  // compare-and-swap build where the device lacks shared float atomics.
  const std::string raster_bwd = block_suffix_.empty() && !ctx_.caps().shared_float_atomic_add
                                     ? "splat/rasterize_bwd_cas"
                                     : "splat/rasterize_bwd" + block_suffix_ + block_bwd_suffix();
  // The compositing backward writes only the slots it visits (Gaussians in front of its tile's
  // last blended one); the others keep these zeros. A fill is a sequential write: far cheaper
  // than the kernel's scattered zero stores (lavapipe, bench raster 100k: backward -6 ms).
  for (size_t k = 0; k < isect_grad_.size(); ++k) cmd_.fill(isect_grad_[k], 0u, 0, isect_grad_bytes(k, st.num_isects_));
  std::vector<gpu::Bind> bindings = {{kRasterBindRanges, st.tile_range_},
                                     {kRasterBindSlots, st.sorted_slots()},
                                     {kRasterBindGid, st.gaussian_id_from_slot_},
                                     {kRasterBindProjA, st.proj_mean_conic_},
                                     {kRasterBindProjB, st.proj_misc_},
                                     {kRasterBindProjC, st.proj_color_},
                                     {kRasterizeBwdBindInT, st.final_T_},
                                     {kRasterizeBwdBindInLast, st.last_isect_},
                                     {kRasterizeBwdBindVRgb, v_rgb},
                                     {kRasterizeBwdBindVAlpha, v_alpha},
                                     {kRasterizeBwdBindG0, plane(0)},
                                     {kRasterizeBwdBindG1, plane(1)},
                                     {kRasterizeBwdBindG2, plane(2)}};
  if (!block_suffix_.empty()) bindings.push_back({kRasterizeBwdBindInBlocks, st.block_words_});
  cmd_.dispatch(raster_bwd, bindings, st.raster_pc_, cmd_.linear_groups(st.raster_pc_.tiles_x * st.raster_pc_.tiles_y));
  cmd_.mark("rasterize backward");
  ProjectPC pp = st.project_pc_;
  pp.flags = accumulate ? (pp.flags | kFlagAccumulate) : (pp.flags & ~kFlagAccumulate);
  // project_bwd writes the active SH bands only; an overwrite gets zeros in the bands above.
  if (!accumulate)
    for (int l = int(pp.sh_degree) + 1; l <= grads.sh_degree; ++l) cmd_.fill(grads.sh[l], 0u);
  std::vector<gpu::Bind> binds = {{kParamBindMeans, params.means},
                                  {kParamBindLogScales, params.log_scales},
                                  {kParamBindQuats, params.quats},
                                  {kParamBindOpacities, params.opacity_logits},
                                  {kProjectBwdBindOffsets, st.isect_offset_},
                                  {kProjectBwdBindG0, plane(0)},
                                  {kProjectBwdBindG1, plane(1)},
                                  {kProjectBwdBindG2, plane(2)},
                                  {kProjectBwdBindVMeans, grads.means},
                                  {kProjectBwdBindVLogScales, grads.log_scales},
                                  {kProjectBwdBindVQuats, grads.quats},
                                  {kProjectBwdBindVOpacities, grads.opacity_logits},
                                  {kProjectBwdBindVSh0, sh_band(grads, 0)},
                                  {kProjectBwdBindVSh1, sh_band(grads, 1)},
                                  {kProjectBwdBindVSh2, sh_band(grads, 2)},
                                  {kProjectBwdBindVSh3, sh_band(grads, 3)},
                                  {kProjectBwdBindGrad2d, grad2d_norm_},
                                  {kProjectBwdBindPosePartial, pose_partial_},
                                  {kProjectBwdBindProjC, st.proj_color_},
                                  {kProjectBwdBindDColor, st.proj_dcolor_}};
  // The accumulating "_block" build reads what it adds to through texel views of the same buffers.
  if (accumulate && !block_suffix_.empty())
    binds.insert(binds.end(), {{kProjectBwdBindVMeansIn, grads.means},
                               {kProjectBwdBindVLogScalesIn, grads.log_scales},
                               {kProjectBwdBindVQuatsIn, grads.quats},
                               {kProjectBwdBindVOpacitiesIn, grads.opacity_logits},
                               {kProjectBwdBindVSh0In, grads.sh[0]},
                               {kProjectBwdBindGrad2dIn, grad2d_norm_}});
  cmd_.dispatch((accumulate ? "splat/project_bwd_acc" : "splat/project_bwd") + block_suffix_, binds, pp,
                cmd_.linear_groups(groups));
  ReducePC rp{pose_partials(params.count), pose_slot, 0, 0};
  cmd_.dispatch("splat/pose_reduce", {{kPoseReduceBindPartials, pose_partial_}, {kPoseReduceBindPose, poses_}}, rp,
                gpu::Groups{1, 1, 1});
  cmd_.mark("project backward");
}

void Rasterizer::drop_backward_stages() {
  stage_ms_.erase(std::remove_if(stage_ms_.begin(), stage_ms_.end(),
                                 [](auto& s) { return s.first.find("backward") != std::string::npos; }),
                  stage_ms_.end());
}

void Rasterizer::backward(const RenderState& st, const GaussianBuffers& params, const gpu::Buffer& v_rgb,
                          const gpu::Buffer& v_alpha, GaussianBuffers& grads, bool accumulate) {
  check_backward(st, params, v_rgb, v_alpha, grads);
  ensure_backward_buffers(params.count, st.num_isects_);
  poses_.ensure(24);
  drop_backward_stages();
  record_backward(st, params, v_rgb, v_alpha, grads, accumulate, 0);
  last_pose_ = 0;
  cmd_.submit();
  for (auto& s : cmd_.stage_ms()) stage_ms_.push_back(s);
}

std::vector<std::array<float, 6>> Rasterizer::backward(const std::vector<const RenderState*>& states,
                                                       const GaussianBuffers& params,
                                                       const std::vector<const gpu::Buffer*>& v_rgb,
                                                       const gpu::Buffer& v_alpha, GaussianBuffers& grads) {
  if (v_rgb.size() != states.size()) throw gpu::Error("Rasterizer::backward: one v_rgb per render expected");
  uint64_t most = 0;
  for (size_t i = 0; i < states.size(); ++i) {
    check_backward(*states[i], params, *v_rgb[i], v_alpha, grads);
    most = std::max<uint64_t>(most, states[i]->num_isects_);
  }
  ensure_backward_buffers(params.count, most);
  poses_.ensure(std::max<uint64_t>(states.size(), 1) * 24);
  drop_backward_stages();
  for (size_t i = 0; i < states.size(); ++i)
    record_backward(*states[i], params, *v_rgb[i], v_alpha, grads, i > 0, uint32_t(i));
  last_pose_ = uint32_t(std::max<size_t>(states.size(), 1) - 1);
  cmd_.submit();
  for (auto& s : cmd_.stage_ms()) stage_ms_.push_back(s);
  std::vector<std::array<float, 6>> out(states.size());
  if (!out.empty()) poses_.download(out.data(), out.size() * 24);
  return out;
}

std::array<float, 6> Rasterizer::pose_gradient() const {
  std::array<float, 6> g;
  poses_.download(g.data(), 24, uint64_t(last_pose_) * 24);
  return g;
}

}  // namespace evflow
