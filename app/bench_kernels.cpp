#include "bench_kernels.h"

#include <algorithm>
#include <cstdio>
#include <set>

#include "bench_stats.h"

namespace evflow::app {

void KernelSamples::add_run(const std::vector<std::pair<std::string, double>>& times) {
  std::map<std::string, std::pair<double, int>> run;
  for (const auto& [kernel, ms] : times) {
    run[kernel].first += ms;
    run[kernel].second += 1;
  }
  runs_.push_back(std::move(run));
}

std::vector<KernelSamples::Row> KernelSamples::rows() const {
  std::set<std::string> kernels;
  for (const auto& run : runs_)
    for (const auto& entry : run) kernels.insert(entry.first);
  std::vector<Row> out;
  for (const std::string& k : kernels) {
    std::vector<double> ms, n;
    for (const auto& run : runs_) {
      auto it = run.find(k);
      ms.push_back(it == run.end() ? 0.0 : it->second.first);
      n.push_back(it == run.end() ? 0.0 : double(it->second.second));
    }
    out.push_back({k, median(ms), median(n)});
  }
  std::stable_sort(out.begin(), out.end(), [](const Row& a, const Row& b) { return a.ms > b.ms; });
  return out;
}

void KernelSamples::print_json() const {
  const std::vector<Row> r = rows();
  std::printf("\"kernels_ms\": {");
  for (size_t i = 0; i < r.size(); ++i) std::printf("%s\"%s\": %.3f", i ? ", " : "", r[i].kernel.c_str(), r[i].ms);
  std::printf("}, \"kernel_dispatches\": {");
  for (size_t i = 0; i < r.size(); ++i)
    std::printf("%s\"%s\": %g", i ? ", " : "", r[i].kernel.c_str(), r[i].dispatches);
  std::printf("}");
}

void KernelSamples::print_text() const {
  double sum = 0;
  std::printf("  kernels (GPU time per run, medians; dispatches per run):\n");
  for (const Row& r : rows()) {
    std::printf("    %-36s %9.3f ms  %5g\n", r.kernel.c_str(), r.ms, r.dispatches);
    sum += r.ms;
  }
  std::printf("    %-36s %9.3f ms\n", "sum of the medians", sum);
}

}  // namespace evflow::app
