#include <catch2/catch.hpp>

#include <algorithm>
#include <cstdlib>
#include <numeric>
#include <random>

#include "gpu_fixture.h"
#include "scan/prefix_sum.h"
#include "sort/radix_sort.h"

using namespace evflow;

TEST_CASE("scan: exclusive prefix sum with total, across block levels", "[gpu][scan]") {
  auto& ctx = test::gpu_context();
  PrefixSum scan(ctx);
  std::mt19937 rng(3);
  // Both workgroup shapes whatever the device (16 x 256 elements on CPU drivers, 256 x 16 on
  // GPUs), lengths that end inside a group of four and across block levels (the wide scan: in
  // one workgroup up to kScanSingleMax elements), into another buffer with the total and in place.
  for (bool wide : {false, true})
    for (uint32_t n :
         {1u, 5u, 1023u, 1024u, 1025u, 4095u, 4097u, 4099u, 30001u, 65535u, 65536u, 65537u, 300000u, 1100000u})
      for (bool in_place : {false, true}) {
        scan.set_wide(wide);
        std::vector<uint32_t> in(n);
        for (auto& v : in) v = rng() % 7;
        gpu::Buffer bin(ctx, n * 4ull, "in"), bout(ctx, (n + 1) * 4ull, "out");
        bin.write(in);
        // The word past n_out keeps what it held.
        if (!in_place) bout.write(std::vector<uint32_t>(n + 1, 0xDEADBEEFu));
        gpu::Commands cmd(ctx);
        const uint32_t n_out = in_place ? n : n + 1;
        scan.record(cmd, bin, in_place ? bin : bout, n, n_out);
        cmd.submit();
        auto out = (in_place ? bin : bout).read<uint32_t>(n_out);
        uint32_t run = 0;
        bool ok = true;
        for (uint32_t i = 0; i < n_out; ++i) {
          ok = ok && out[i] == run;
          if (i < n) run += in[i];
        }
        INFO("n = " << n << (wide ? ", wide" : "") << (in_place ? ", in place" : ""));
        REQUIRE(ok);
      }
  test::require_no_validation_messages();
}

TEST_CASE("sort: stable radix sort on the low bits matches std::stable_sort", "[gpu][sort]") {
  auto& ctx = test::gpu_context();
  RadixSort sort(ctx);
  std::mt19937 rng(11);
  // Both digit widths (4 bits on GPUs, 8 on CPU drivers: the last pass of 12 or 20 bits is
  // narrower, and junk above `bits` must not be sorted on) and several block sizes (16 keys per
  // invocation on GPUs, up to 4096 on CPU drivers; 7, not a multiple of the four keys a vector
  // read takes, for the one-by-one path) whatever the device, and the device's own choice
  // (on CPU drivers blocks in whole rounds of the CPU threads, as long as the keys allow).
  for (uint32_t digit_bits : {4u, 8u, 0u})
    for (uint32_t items : {16u, 128u, 7u, 4096u, 0u})
      for (auto [n, bits] : std::vector<std::pair<uint32_t, uint32_t>>{{1, 8},
                                                                       {300, 0},
                                                                       {17, 4},
                                                                       {4096, 12},
                                                                       {4097, 32},
                                                                       {16385, 8},
                                                                       {70000, 16},
                                                                       {250000, 20},
                                                                       {600000, 32}}) {
        sort.set_digit_bits(digit_bits);
        sort.set_items(items);
        std::vector<uint32_t> keys(n), vals(n);
        // Few distinct keys in the sorted bits so stability is exercised; junk above `bits`.
        for (auto& k : keys) k = (rng() % 977) * 2654435761u;
        std::iota(vals.begin(), vals.end(), 0u);
        gpu::Buffer bk(ctx, n * 4ull, "keys"), bv(ctx, n * 4ull, "values");
        bk.write(keys);
        bv.write(vals);
        const uint32_t mask = bits >= 32 ? 0xFFFFFFFFu : ((1u << bits) - 1u);
        // Expected: stable sort of indices by (key & mask). Bits above are not sorted on.
        std::vector<uint32_t> order(n);
        std::iota(order.begin(), order.end(), 0u);
        std::stable_sort(order.begin(), order.end(),
                         [&](uint32_t a, uint32_t b) { return (keys[a] & mask) < (keys[b] & mask); });
        // record sorts the given values; record_order makes the permutation itself (the values'
        // buffer holds junk first, to show it is not read).
        for (bool make_order : {false, true}) {
          gpu::Commands cmd(ctx);
          gpu::Buffer k_alt(ctx, 4, "keys_alt"), v_alt(ctx, 4, "values_alt");
          if (make_order) bv.write(std::vector<uint32_t>(n, 0xDEADBEEFu));
          auto [sk, sv] =
              make_order ? sort.record_order(cmd, bk, bv, k_alt, v_alt, n, bits) : sort.record(cmd, bk, bv, n, bits);
          cmd.submit();
          auto gk = sk->read<uint32_t>(n);
          auto gv = sv->read<uint32_t>(n);
          bool ok = true;
          for (uint32_t i = 0; i < n; ++i) ok = ok && gv[i] == order[i] && gk[i] == keys[order[i]];
          INFO("n = " << n << ", bits = " << bits << ", items " << items << ", digit bits " << digit_bits
                      << (make_order ? ", record_order" : ", record"));
          REQUIRE(ok);
          if (!make_order) bk.write(keys);  // an even pass count sorted the caller's buffer in place
        }
      }
  CHECK_THROWS_WITH(sort.set_digit_bits(5), Catch::Contains("4 or 8"));
  test::require_no_validation_messages();
}
