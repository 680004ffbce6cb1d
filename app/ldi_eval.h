// The LDI branch's own deblurring score for `evflow eval`: each training view's LDI frame at
// mid-exposure (B / E(t_N), over the whole view) against the sharp mid-exposure image, on 8-bit
// sRGB as the splats' renders are scored; the frames go to RUN/eval/ldi/<view>.png.
#pragma once
#include <nlohmann/json.hpp>

#include "gpu/context.h"
#include "io/dataset.h"
#include "run_files.h"
#include "train/train_config.h"

namespace evflow::app {

// The "ldi" set of eval.json ({views: [{view, psnr, ssim}], mean_psnr, mean_ssim}), or null for
// a run without the LDI branch. Reads RUN/ldi.safetensors (errors name it).
nlohmann::json score_ldi_frames(gpu::Context& ctx, const RunFolder& run, const io::Dataset& data,
                                const TrainConfig& cfg);

}  // namespace evflow::app
