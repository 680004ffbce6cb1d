#pragma once
// Per-kernel GPU times of a bench (--kernels, gpu::ContextOptions::kernel_times): each run's
// (step's, repeat's) time and dispatches per kernel, reported as medians over the runs.
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace evflow::app {

class KernelSamples {
 public:
  // One run's dispatches (Context::take_kernel_times), summed per kernel.
  void add_run(const std::vector<std::pair<std::string, double>>& times);
  // Each kernel's median over the runs of its summed time (a run without it counts 0), and of its
  // dispatches per run; slowest first.
  struct Row {
    std::string kernel;
    double ms = 0, dispatches = 0;
  };
  std::vector<Row> rows() const;
  // `"kernels_ms": {...}, "kernel_dispatches": {...}` (JSON members, no braces around them).
  void print_json() const;
  // A table, one line per kernel, and the sum of the medians.
  void print_text() const;

 private:
  std::vector<std::map<std::string, std::pair<double, int>>> runs_;  // kernel -> (ms, dispatches)
};

}  // namespace evflow::app
