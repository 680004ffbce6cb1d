// Double-precision CPU reference of the flow estimator's contrast (engine/flow/flow_estimator.h):
// the same warp, bilinear vote, Gaussian blur and squared central-difference gradient, without
// the GPU's fixed-point votes.
#pragma once
#include <vector>

#include "flow/flow_estimator.h"

namespace evflow::reference {

// sum over references r of scale[r] * G_r(grids), one grid per interval between consecutive
// frame_u; the IWEs `image_scale` times coarser than the sensor, from the events whose index (in
// the pixel-by-pixel order) is a multiple of `stride`.
double flow_contrast(const flow::PixelEvents& ev, const std::vector<double>& frame_u,
                     const std::vector<flow::FlowGrid>& grids, const std::vector<double>& scale, int image_scale = 1,
                     uint32_t stride = 1);

// G of one image: sum of squared central differences of its Gaussian blur (kFlowBlurRadius) (zero outside).
double flow_image_contrast(const std::vector<double>& iwe, int width, int height);

}  // namespace evflow::reference
