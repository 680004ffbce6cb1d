#pragma once
// The statistic every bench prints for repeated timings.
#include <algorithm>
#include <vector>

namespace evflow::app {

// The median of the values: for an even count the upper of the two middle values (a time one run
// took, not an average of two), 0 for none. Medians of separate stages therefore need not add up
// to the median of their sum.
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

}  // namespace evflow::app
