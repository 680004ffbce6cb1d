// evflow bench conv: forward and backward of a stack of 3x3 convolutions (the LDI network's
// layers), per-layer milliseconds and GFLOP/s.
#pragma once
#include "cli.h"

namespace evflow::app {

int bench_conv(ArgParser& p);

}  // namespace evflow::app
