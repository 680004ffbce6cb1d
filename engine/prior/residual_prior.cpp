#include "prior/residual_prior.h"

#include <filesystem>
#include <stdexcept>

#include "gpu/commands.h"
#include "prior/event_inputs.h"
#include "prior/residual_net.h"

namespace evflow::prior {

std::string resolve_weights_path(const std::string& path) {
  namespace fs = std::filesystem;
  if (fs::exists(path) || fs::path(path).is_absolute()) return path;
  const fs::path in_source = fs::path(EVF_SOURCE_DIR) / path;
  return fs::exists(in_source) ? in_source.string() : path;
}

std::vector<std::vector<float>> predict_residuals(gpu::Context& ctx, const std::string& weights_path,
                                                  const io::Dataset& data, const std::vector<double>& u) {
  if (data.train.empty()) throw std::invalid_argument("residual prior: the dataset has no training views");
  if (data.events.size() == 0)
    throw std::invalid_argument("residual prior: the dataset in '" + data.root + "' has no events with times");
  const std::string path = resolve_weights_path(weights_path);
  const io::Image& first = data.train[0].blurry;
  auto net = load_residual_net(ctx, path, first.height, first.width);
  if (net->spec().frames != u.size())
    throw std::invalid_argument(path + ": the residual prior predicts " + std::to_string(net->spec().frames) +
                                " virtual frames, the training uses " + std::to_string(u.size()) +
                                " (virtual_frames=" + std::to_string(net->spec().frames / 2) + ")");
  gpu::Commands cmd(ctx);
  std::vector<std::vector<float>> out;
  for (const io::View& v : data.train) {
    if (v.blurry.width != first.width || v.blurry.height != first.height || v.blurry.channels != 3)
      throw std::invalid_argument("residual prior: view '" + v.name + "' is not RGB of the first view's size");
    const auto planes = event_planes(data.events, v.exposure_start, v.exposure_end, u);
    net->input().upload(network_input(v.blurry.data, planes, first.width, first.height));
    net->forward(cmd);
    cmd.submit();
    out.push_back(net->output().download());
  }
  return out;
}

}  // namespace evflow::prior
