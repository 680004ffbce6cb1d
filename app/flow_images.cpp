#include "flow_images.h"

#include <algorithm>
#include <cmath>

namespace evflow::app {

std::vector<uint8_t> grey_image(const std::vector<float>& v, double scale) {
  std::vector<uint8_t> g(v.size());
  for (size_t i = 0; i < v.size(); ++i) g[i] = uint8_t(std::lround(255 * std::clamp(v[i] / scale, 0.0, 1.0)));
  return g;
}

double image_variance(const std::vector<float>& v) {
  double s = 0, s2 = 0;
  for (float x : v) s += x, s2 += double(x) * x;
  const double n = double(std::max<size_t>(1, v.size())), m = s / n;
  return s2 / n - m * m;
}

}  // namespace evflow::app
