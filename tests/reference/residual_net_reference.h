// Double-precision CPU reference of the residual prior's U-Net (engine/prior/residual_net.h),
// composed from the layer references (nn_reference.h).
#pragma once
#include <cstdint>
#include <vector>

#include "reference/nn_reference.h"

namespace evflow::ref {

struct UnetLayer {
  std::vector<double> weight, bias;  // weight [out][in][k][k]
  uint32_t out_c = 0, ksize = 3, stride = 1;
};

// Layers in the network's order: enc0, down1, enc1, down2, enc2, dec1, dec0, out.
NnTensor residual_unet(const NnTensor& x, const std::vector<UnetLayer>& layers);

}  // namespace evflow::ref
