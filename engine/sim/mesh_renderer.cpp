#include "sim/mesh_renderer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "io/image.h"
#include "sim/sim_layout.h"

namespace evflow::sim {

using namespace shaderio;

MeshRenderer::MeshRenderer(gpu::Context& ctx, const Scene& scene, const ShadingParams& shading)
    : ctx_(ctx), shading_(shading), small_box_(kSimSmallBox), cmd_(ctx), scan_(ctx) {
  scene.validate();
  const size_t T = scene.triangle_count();
  if (T == 0) throw std::runtime_error(scene.source + ": no triangles to render");
  if (T >= (1u << 24)) throw std::runtime_error(scene.source + ": too many triangles (" + std::to_string(T) + ")");
  n_tris_ = uint32_t(T);
  std::vector<SimTriangle> tris(T);
  for (size_t i = 0; i < T; ++i) {
    const float* p = &scene.positions[i * 9];
    const float* uv = &scene.uvs[i * 6];
    tris[i].p0 = glm::vec4(p[0], p[1], p[2], float(scene.material[i]));
    tris[i].p1 = glm::vec4(p[3], p[4], p[5], 0.f);
    tris[i].p2 = glm::vec4(p[6], p[7], p[8], 0.f);
    tris[i].uv01 = glm::vec4(uv[0], uv[1], uv[2], uv[3]);
    tris[i].uv2 = glm::vec4(uv[4], uv[5], 0.f, 0.f);
  }
  std::vector<SimMaterial> mats(scene.materials.size());
  std::vector<uint32_t> texels;
  std::vector<uint32_t> tex_offset;
  std::vector<uint32_t> tex_levels;
  for (auto& t : scene.textures) {
    tex_offset.push_back(uint32_t(texels.size()));
    // Mip chain: 2x2 box filter in linear space (clamped at odd edges), re-encoded as sRGB.
    std::vector<uint32_t> level = t.rgba;
    uint32_t w = t.width, h = t.height, levels = 1;
    texels.insert(texels.end(), level.begin(), level.end());
    while ((w > 1 || h > 1) && levels < 16) {
      const uint32_t nw = std::max(1u, w / 2), nh = std::max(1u, h / 2);
      std::vector<uint32_t> next(size_t(nw) * nh);
      for (uint32_t y = 0; y < nh; ++y)
        for (uint32_t x = 0; x < nw; ++x) {
          float acc[4] = {0, 0, 0, 0};
          for (uint32_t dy = 0; dy < 2; ++dy)
            for (uint32_t dx = 0; dx < 2; ++dx) {
              const uint32_t sx = std::min(2 * x + dx, w - 1), sy = std::min(2 * y + dy, h - 1);
              const uint32_t c = level[size_t(sy) * w + sx];
              for (int k = 0; k < 3; ++k) acc[k] += io::srgb_to_linear(((c >> (8 * k)) & 255u) / 255.f);
              acc[3] += (c >> 24) / 255.f;
            }
          uint32_t out = 0;
          for (int k = 0; k < 4; ++k) {
            const float v = k < 3 ? io::linear_to_srgb(0.25f * acc[k]) : 0.25f * acc[k];
            out |= uint32_t(std::lround(std::clamp(v, 0.f, 1.f) * 255.f)) << (8 * k);
          }
          next[size_t(y) * nw + x] = out;
        }
      texels.insert(texels.end(), next.begin(), next.end());
      level.swap(next);
      w = nw;
      h = nh;
      ++levels;
    }
    tex_levels.push_back(levels);
  }
  if (texels.empty()) texels.push_back(0xFFFFFFFFu);
  for (size_t i = 0; i < mats.size(); ++i) {
    const auto& m = scene.materials[i];
    mats[i].factor = glm::vec4(m.base_color[0], m.base_color[1], m.base_color[2], m.base_color[3]);
    if (m.texture >= 0) {
      const auto& t = scene.textures[m.texture];
      mats[i].tex = glm::uvec4(tex_offset[m.texture], t.width, t.height,
                               t.wrap_s | (t.wrap_t << 2) | (tex_levels[m.texture] << 8));
    } else {
      mats[i].tex = glm::uvec4(kSimNoTexture, 1, 1, 1u << 8);
    }
  }
  ctx.check_binding_size(T * sizeof(SimTriangle), scene.source + " triangles");
  ctx.check_binding_size(texels.size() * 4, scene.source + " textures");
  tris_ = gpu::Buffer(ctx, T * sizeof(SimTriangle), "sim_tris");
  tris_.write(tris);
  materials_ = gpu::Buffer(ctx, mats.size() * sizeof(SimMaterial), "sim_materials");
  materials_.write(mats);
  texels_ = gpu::Buffer(ctx, texels.size() * 4, "sim_texels");
  texels_.write(texels);
  std::vector<float> decode(kSimDecodeEntries);  // sim/shade's sRGB decode of the 8-bit codes
  for (uint32_t c = 0; c < kSimDecodeEntries; ++c) decode[c] = io::srgb_to_linear(float(c) / 255.f);
  decode_ = gpu::Buffer(ctx, decode.size() * 4, "sim_srgb_decode");
  decode_.write(decode);
  cam_ = gpu::Buffer(ctx, T * 48, "sim_cam_verts");
  boxes_ = gpu::Buffer(ctx, T * 16, "sim_boxes");
  counts_ = gpu::Buffer(ctx, T * 4, "sim_counts");
  offsets_ = gpu::Buffer(ctx, (T + 1) * 4, "sim_offsets");
  depth_ = gpu::Buffer(ctx, 16, "sim_depth");
  ids_ = gpu::Buffer(ctx, 16, "sim_ids");
  image_ = gpu::Buffer(ctx, 16, "sim_image");
}

Frame MeshRenderer::render(const Camera& c) {
  const uint32_t W = c.width, H = c.height;
  if (W == 0 || H == 0) throw std::invalid_argument("MeshRenderer::render: empty image size");
  const uint64_t P = uint64_t(W) * H;
  depth_.ensure(P * 4);
  ids_.ensure(P * 4);
  image_.ensure(P * 16);
  SimPC pc{};
  pc.r0 = glm::vec4(float(c.R[0]), float(c.R[1]), float(c.R[2]), float(c.t[0]));
  pc.r1 = glm::vec4(float(c.R[3]), float(c.R[4]), float(c.R[5]), float(c.t[1]));
  pc.r2 = glm::vec4(float(c.R[6]), float(c.R[7]), float(c.R[8]), float(c.t[2]));
  pc.intr = glm::vec4(float(c.fx), float(c.fy), float(c.cx), float(c.cy));
  auto L = shading_.light_dir;
  const float ln = std::sqrt(L[0] * L[0] + L[1] * L[1] + L[2] * L[2]);
  pc.light = glm::vec4(L[0] / ln, L[1] / ln, L[2] / ln, shading_.ambient);
  pc.background = glm::vec4(shading_.background[0], shading_.background[1], shading_.background[2], 0.f);
  pc.dims = glm::uvec4(W, H, n_tris_, 0);
  pc.misc = glm::vec4(float(std::max(c.near_plane, 1e-6)), float(shading_.texture_samples >= 4 ? 4 : 1),
                      float(small_box_), 0.f);

  stage_ms_.clear();
  auto keep_stages = [&] { stage_ms_.insert(stage_ms_.end(), cmd_.stage_ms().begin(), cmd_.stage_ms().end()); };
  cmd_.dispatch("sim/tri_setup",
                {{kSimTriSetupBindTris, tris_},
                 {kSimTriSetupBindCamVerts, cam_},
                 {kSimTriSetupBindBoxes, boxes_},
                 {kSimTriSetupBindCounts, counts_}},
                pc, cmd_.linear_groups(gpu::Commands::div_up(n_tris_, kSimSetupGroupSize)));
  cmd_.mark("setup");
  scan_.record(cmd_, counts_, offsets_, n_tris_, n_tris_ + 1);
  cmd_.mark("scan");
  cmd_.fill(depth_, 0xFFFFFFFFu, 0, P * 4);
  cmd_.fill(ids_, kSimNoTriangle, 0, P * 4);
  cmd_.mark("clear");
  cmd_.submit();
  keep_stages();
  const uint32_t items = offsets_.read_one<uint32_t>(n_tris_);
  // Pass 0 keeps each pixel's nearest depth, pass 1 the triangle at that depth.
  for (uint32_t pass = 0; pass < 2; ++pass) {
    pc.dims.w = pass;
    if (small_box_ > 0)
      cmd_.dispatch("sim/raster_small",
                    {{kSimRasterBindCamVerts, cam_},
                     {kSimRasterBindBoxes, boxes_},
                     {kSimRasterBindDepth, depth_},
                     {kSimRasterBindIds, ids_}},
                    pc, cmd_.linear_groups(gpu::Commands::div_up(n_tris_, kSimSmallGroupSize)));
    cmd_.mark(pass == 0 ? "raster small (depth)" : "raster small (id)");
    if (items > 0)
      cmd_.dispatch("sim/raster",
                    {{kSimRasterBindCamVerts, cam_},
                     {kSimRasterBindBoxes, boxes_},
                     {kSimRasterBindOffsets, offsets_},
                     {kSimRasterBindDepth, depth_},
                     {kSimRasterBindIds, ids_}},
                    pc, cmd_.linear_groups(items));
    cmd_.mark(pass == 0 ? "raster tiles (depth)" : "raster tiles (id)");
  }
  cmd_.dispatch("sim/shade",
                {{kSimShadeBindTris, tris_},
                 {kSimShadeBindCamVerts, cam_},
                 {kSimShadeBindIds, ids_},
                 {kSimShadeBindMaterials, materials_},
                 {kSimShadeBindTexels, texels_},
                 {kSimShadeBindOut, image_},
                 {kSimShadeBindDecode, decode_}},
                pc, cmd_.linear_groups(gpu::Commands::div_up(P, kSimShadeGroupSize)));
  cmd_.mark("shade");
  cmd_.submit();
  keep_stages();
  std::vector<float> px = image_.read<float>(P * 4);
  Frame f;
  f.width = W;
  f.height = H;
  f.rgb.resize(P * 3);
  f.depth.resize(P);
  for (uint64_t i = 0; i < P; ++i) {
    f.rgb[i * 3] = px[i * 4];
    f.rgb[i * 3 + 1] = px[i * 4 + 1];
    f.rgb[i * 3 + 2] = px[i * 4 + 2];
    f.depth[i] = px[i * 4 + 3];
  }
  return f;
}

}  // namespace evflow::sim
