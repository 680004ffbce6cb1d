// `evflow train-prior`: simulates the residual prior's data in procedural rooms, trains the
// residual U-Net (engine/prior) and writes its weights as safetensors, with the held-out error
// against the zero residual and the EDI baseline.
#include <algorithm>
#include <cstdio>
#include <numeric>

#include "cli.h"
#include "nn/safetensors.h"
#include "prior/prior_training.h"

namespace evflow::app {

namespace {

void print_help() {
  std::printf(
      "usage: evflow train-prior --out FILE.safetensors [--rooms 12] [--held-out-rooms 2] [--room-seed 1000]\n"
      "                          [--views 8] [--width 173] [--height 130] [--net-width 16] [--steps 2000]\n"
      "                          [--crop 64] [--batch 4] [--lr 0.001] [--seed 1] [--minutes 0] [--log-every 25]\n"
      "                          [--device N|name]\n"
      "Rooms room-seed .. room-seed + rooms - 1 train, the next held-out-rooms score; --minutes > 0 stops\n"
      "training when that much wall time has passed.\n");
}

std::vector<uint64_t> seeds(uint64_t first, uint64_t count) {
  std::vector<uint64_t> v(count);
  std::iota(v.begin(), v.end(), first);
  return v;
}

std::string command_line(const Args& a) {
  std::string s = "evflow train-prior";
  for (const auto& x : a) s += " " + x;
  return s;
}

}  // namespace

static int run_train_prior(const Args& a) {
  ArgParser p(a);
  if (p.flag("--help")) return print_help(), 0;
  const std::string out = p.value("--out");
  const uint64_t rooms = uint64_t(p.integer("--rooms", 12, 1, 100000)),
                 held = uint64_t(p.integer("--held-out-rooms", 2, 0, 100000));
  const uint64_t first_room = uint64_t(p.integer("--room-seed", 1000, 0, 1000000000));
  prior::SampleOptions so;
  so.views_per_room = int(p.integer("--views", 8, 1, 100000));
  const ImageSize size = p.image_size({173, 130});
  so.width = size.width;
  so.height = size.height;
  prior::ResidualNetSpec spec;
  spec.width = uint32_t(p.integer("--net-width", 16, 1, 1024));
  prior::PriorTrainOptions o;
  o.steps = uint32_t(p.integer("--steps", 2000, 1, 100000000));
  o.crop = uint32_t(p.integer("--crop", 64, 1, kMaxImageSide));
  o.batch = uint32_t(p.integer("--batch", 4, 1, 4096));
  o.lr = float(p.number("--lr", 1e-3));
  if (!(o.lr > 0)) throw std::invalid_argument("--lr must be positive");
  o.seed = uint64_t(p.integer("--seed", 1));
  o.max_seconds = 60.0 * p.number("--minutes", 0);
  const uint32_t log_every = uint32_t(std::max<long long>(1, p.integer("--log-every", 25)));
  gpu::ContextOptions co = context_options(p);
  p.reject_unknown();
  if (out.empty()) throw std::invalid_argument("train-prior: --out FILE.safetensors is required");
  if (rooms < 1 || held < 1)
    throw std::invalid_argument("train-prior: needs at least one training and one held-out room");
  gpu::Context ctx(co);

  std::printf("%s\nsimulating %llu training rooms (seeds %llu..%llu) and %llu held-out rooms, %d views each, %ux%u\n",
              command_line(a).c_str(), (unsigned long long)rooms, (unsigned long long)first_room,
              (unsigned long long)(first_room + rooms - 1), (unsigned long long)held, so.views_per_room, so.width,
              so.height);
  std::fflush(stdout);
  const auto train = prior::simulate_samples(ctx, seeds(first_room, rooms), so, false);
  const auto test = prior::simulate_samples(ctx, seeds(first_room + rooms, held), so, true);
  prior::ResidualNet net(ctx, spec, o.crop, o.crop);
  net.init_he(o.seed);
  std::printf("%s: %llu parameters; %zu training views, %zu held-out views\n", spec.str().c_str(),
              (unsigned long long)net.parameter_count(), train.size(), test.size());
  double window = 0;
  const uint32_t steps = prior::train_prior(ctx, net, train, o, [&](const prior::StepLog& l) {
    window += l.loss;
    if (l.step % log_every) return;
    std::printf("step %u  loss %.4e  (%.0f s)\n", l.step, window / log_every, l.seconds);
    std::fflush(stdout);
    window = 0;
  });
  const prior::ResidualErrors e = prior::score_prior(ctx, net, test);
  std::printf("held-out residual MSE over %zu values: network %.4e, zero residual %.4e, EDI %.4e\n", e.values,
              e.network, e.zero, e.edi);
  nn::SafetensorsFile f = net.save();
  f.metadata["command"] = command_line(a);
  f.metadata["steps"] = std::to_string(steps);
  f.metadata["heldout_mse"] = std::to_string(e.network);
  f.metadata["heldout_mse_zero"] = std::to_string(e.zero);
  f.metadata["heldout_mse_edi"] = std::to_string(e.edi);
  nn::save_safetensors(out, f);
  std::printf("wrote %s\n", out.c_str());
  return 0;
}

static Command reg("train-prior",
                   "train the residual prior's U-Net on simulated procedural rooms and write its weights",
                   run_train_prior);

}  // namespace evflow::app
