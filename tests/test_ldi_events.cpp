// The LDI's event preprocessing P(.) (engine/ldi/event_bins.h) on hand-made events: every bin,
// both polarities, both sides, the edges t_0 (in) and t_2N (out), crops and a second view.
#include <catch2/catch.hpp>

#include <map>
#include <tuple>

#include "events/gpu_events.h"
#include "gpu/commands.h"
#include "gpu_fixture.h"
#include "ldi/event_bins.h"

using namespace evflow;

namespace {

// (channel, y, x) -> count; every other entry of the tensor must be 0.
using Entries = std::map<std::tuple<uint32_t, uint32_t, uint32_t>, float>;

EventStream hand_events() {
  EventStream ev;
  ev.width = 4, ev.height = 3;
  ev.push(0, 0, 0.0, 1);    // t_0 exactly
  ev.push(1, 1, 0.52, 1);   //
  ev.push(1, 0, 0.79, -1);  //
  ev.push(2, 1, 0.8, 1);    // t_i = 0.8 exactly: the side after
  ev.push(2, 1, 0.81, 1);   //
  ev.push(3, 2, 1.02, -1);  //
  ev.push(3, 2, 1.59, 1);   //
  ev.push(0, 0, 1.6, 1);    // t_2N: outside the window [0, 1.6)
  return ev;
}

std::vector<float> side_tensor(gpu::Commands& cmd, const GpuEvents& ev, size_t view, double t_i, ldi::Side side,
                               const ldi::Crop& crop) {
  const size_t n = crop.pixels() * 32;
  gpu::Buffer out(test::gpu_context(), n * 4, "ldi_side");
  ldi::record_side_tensor(cmd, ev, view, t_i, side, crop, out);
  cmd.submit();
  return out.read<float>(n);
}

void require_tensor(const std::vector<float>& got, const ldi::Crop& crop, uint32_t channels, const Entries& want) {
  REQUIRE(got.size() == size_t(channels) * crop.pixels());
  for (uint32_t c = 0; c < channels; ++c)
    for (uint32_t y = 0; y < crop.h; ++y)
      for (uint32_t x = 0; x < crop.w; ++x) {
        auto it = want.find({c, y, x});
        INFO("channel " << c << " y " << y << " x " << x);
        CHECK(got[(size_t(c) * crop.h + y) * crop.w + x] == (it == want.end() ? 0.0f : it->second));
      }
}

}  // namespace

TEST_CASE("LDI events: 16 bins x 2 polarities per side, the side before reversed and flipped", "[ldi][gpu]") {
  auto& ctx = test::gpu_context();
  const EventStream ev = hand_events();
  GpuEvents gpu_ev(ctx, ev, {{0.0, 1.6}, {0.79, 1.2}}, "hand-made events");
  gpu::Commands cmd(ctx);
  const ldi::Crop full{0, 0, 4, 3};

  // t_i = 0.8 of [0, 1.6): both sides 0.8 long, bins of 0.05.
  // Before: t = 0.79 is 0.01 from t_i (bin 0), 0.52 is 0.28 (bin 5), t_0 = 0 is 0.8 (bin 15);
  // polarities flipped: the negative event at 0.79 lands in channel 0, the positive ones in 2 k + 1.
  require_tensor(side_tensor(cmd, gpu_ev, 0, 0.8, ldi::Side::Before, full), full, 32,
                 {{{0, 0, 1}, 1.0f}, {{11, 1, 1}, 1.0f}, {{31, 0, 0}, 1.0f}});
  // After: 0.8 and 0.81 in bin 0 (positive, channel 0), 1.02 in bin 4 (negative, channel 9),
  // 1.59 in bin 15 (channel 30); the event at t_2N = 1.6 is outside.
  require_tensor(side_tensor(cmd, gpu_ev, 0, 0.8, ldi::Side::After, full), full, 32,
                 {{{0, 1, 2}, 2.0f}, {{9, 2, 3}, 1.0f}, {{30, 2, 3}, 1.0f}});

  // A crop: pixels x 1..3, y 0..1, at the crop's own coordinates.
  const ldi::Crop crop{1, 0, 3, 2};
  require_tensor(side_tensor(cmd, gpu_ev, 0, 0.8, ldi::Side::Before, crop), crop, 32,
                 {{{0, 0, 0}, 1.0f}, {{11, 1, 0}, 1.0f}});
  require_tensor(side_tensor(cmd, gpu_ev, 0, 0.8, ldi::Side::After, crop), crop, 32, {{{0, 1, 1}, 2.0f}});

  // t_i = t_0: the side before is empty, the side after spans the exposure (bins of 0.1).
  require_tensor(side_tensor(cmd, gpu_ev, 0, 0.0, ldi::Side::Before, full), full, 32, {});
  require_tensor(side_tensor(cmd, gpu_ev, 0, 0.0, ldi::Side::After, full), full, 32,
                 {{{0, 0, 0}, 1.0f},
                  {{10, 1, 1}, 1.0f},
                  {{15, 0, 1}, 1.0f},
                  {{16, 1, 2}, 2.0f},
                  {{21, 2, 3}, 1.0f},
                  {{30, 2, 3}, 1.0f}});
  // t_i = t_2N: the mirror image, every event before.
  require_tensor(side_tensor(cmd, gpu_ev, 0, 1.6, ldi::Side::After, full), full, 32, {});
  require_tensor(side_tensor(cmd, gpu_ev, 0, 1.6, ldi::Side::Before, full), full, 32,
                 {{{31, 0, 0}, 1.0f},
                  {{21, 1, 1}, 1.0f},
                  {{16, 0, 1}, 1.0f},
                  {{15, 1, 2}, 2.0f},
                  {{10, 2, 3}, 1.0f},
                  {{1, 2, 3}, 1.0f}});

  // The second view's window [0.79, 1.2) at its start: bins of 0.41 / 16 = 0.025625.
  require_tensor(side_tensor(cmd, gpu_ev, 1, 0.79, ldi::Side::After, full), full, 32,
                 {{{1, 0, 1}, 1.0f}, {{0, 1, 2}, 2.0f}, {{17, 2, 3}, 1.0f}});

  // The event loss's counts over a crop, into plane 1: [positive][negative] of [0.5, 1.2).
  gpu::Buffer counts(ctx, 2 * 2 * full.pixels() * 4, "ldi_counts");
  cmd.fill(counts, 0u);
  ldi::record_crop_counts(cmd, gpu_ev, 0, 0.5, 1.2, full, counts, 1);
  cmd.submit();
  const auto c = counts.read<uint32_t>(4 * full.pixels());
  std::vector<uint32_t> want(4 * full.pixels(), 0u);
  want[24 + 1 * 4 + 1] = 1;  // + at (1, 1)
  want[24 + 1 * 4 + 2] = 2;  // + + at (2, 1)
  want[36 + 0 * 4 + 1] = 1;  // - at (1, 0)
  want[36 + 2 * 4 + 3] = 1;  // - at (3, 2)
  CHECK(c == want);

  CHECK_THROWS_WITH(ldi::side_bounds(gpu_ev, 1, 0.5, ldi::Side::After), Catch::Contains("outside view 1"));
  gpu::Buffer small(ctx, 32 * 4 * 4, "ldi_small");
  CHECK_THROWS_WITH(ldi::record_side_tensor(cmd, gpu_ev, 0, 0.8, ldi::Side::After, {2, 0, 3, 1}, small),
                    Catch::Contains("leaves the 4x3 image"));
  test::require_no_validation_messages();
}
