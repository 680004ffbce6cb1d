#include "ldi_eval.h"

#include <cstdio>
#include <stdexcept>

#include "camera/trajectory.h"
#include "metrics/srgb_metrics.h"
#include "nn/safetensors.h"
#include "train/ldi_branch.h"

namespace evflow::app {

namespace fs = std::filesystem;

nlohmann::json score_ldi_frames(gpu::Context& ctx, const RunFolder& run, const io::Dataset& data,
                                const TrainConfig& cfg) {
  if (!cfg.ldi) return nullptr;
  const fs::path path = run.dir / "ldi.safetensors";
  if (!fs::exists(path))
    throw std::runtime_error(path.string() + ": missing; an ldi=on run keeps the LDI's state there");
  const nn::SafetensorsFile state = nn::load_safetensors(path);
  const std::vector<double> u = ExposureTrajectory::virtual_times(int(cfg.virtual_frames));
  LdiBranch ldi(ctx, data, cfg, u, &state, path.string());
  gpu::Commands cmd(ctx);
  const size_t mid = u.size() / 2;
  fs::create_directories(run.dir / "eval" / "ldi");
  nlohmann::json per = nlohmann::json::array();
  double sp = 0, ss = 0;
  for (uint32_t vi = 0; vi < data.train.size(); ++vi) {
    const io::View& v = data.train[vi];
    if (!v.sharp_mid) continue;
    const std::vector<float> frame = ldi.view_frames(cmd, vi, {uint32_t(mid)}).at(0);  // planar linear RGB
    const metrics::Image8 ldi8 = metrics::encode_linear(frame, v.camera.width, v.camera.height, 3);
    const metrics::Image8 gt8 =
        metrics::encode_linear(io::planar_rgb(*v.sharp_mid), v.sharp_mid->width, v.sharp_mid->height, 3);
    metrics::write_png(run.dir / "eval" / "ldi" / (v.name + ".png"), ldi8);
    const metrics::Scores s = metrics::score(ldi8, gt8);
    per.push_back({{"view", v.name}, {"psnr", s.psnr}, {"ssim", s.ssim}});
    sp += s.psnr, ss += s.ssim;
  }
  if (per.empty()) return nullptr;
  const double n = double(per.size());
  std::printf("%-8s %3zu views  PSNR %.2f dB  SSIM %.4f  (the LDI's mid-exposure frames)\n", "ldi", per.size(), sp / n,
              ss / n);
  return {{"views", per}, {"mean_psnr", sp / n}, {"mean_ssim", ss / n}};
}

}  // namespace evflow::app
