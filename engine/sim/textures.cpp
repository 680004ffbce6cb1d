#include "sim/textures.h"

#include <algorithm>
#include <cmath>

#include "io/image.h"

namespace evflow::sim {

namespace {

struct Rng {
  uint64_t s;
  uint64_t next() {
    s += 0x9E3779B97F4A7C15ull;
    uint64_t z = s;
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uni() { return (next() >> 11) * (1.0 / 9007199254740992.0); }
};

uint32_t hash2(int x, int y, uint32_t seed) {
  uint32_t h = uint32_t(x) * 0x8da6b343u ^ uint32_t(y) * 0xd8163841u ^ seed * 0xcb1ab31fu;
  h ^= h >> 13;
  h *= 0x5bd1e995u;
  h ^= h >> 15;
  return h;
}
// Smooth value noise in [0, 1] with period `period` cells.
double value_noise(double x, double y, uint32_t seed, int period) {
  const int xi = int(std::floor(x)), yi = int(std::floor(y));
  const double fx = x - xi, fy = y - yi;
  auto v = [&](int a, int b) {
    return (hash2(((a % period) + period) % period, ((b % period) + period) % period, seed) & 0xFFFF) / 65535.0;
  };
  const double sx = fx * fx * (3 - 2 * fx), sy = fy * fy * (3 - 2 * fy);
  return (v(xi, yi) * (1 - sx) + v(xi + 1, yi) * sx) * (1 - sy) +
         (v(xi, yi + 1) * (1 - sx) + v(xi + 1, yi + 1) * sx) * sy;
}
double fbm(double u, double v, uint32_t seed, int base_period) {
  double s = 0, a = 0.5;
  int p = base_period;
  for (int o = 0; o < 4; ++o, a *= 0.5, p *= 2) s += a * value_noise(u * p, v * p, seed + o, p);
  return s / 0.9375;
}

struct LinearTex {
  uint32_t w, h;
  std::vector<float> rgb;
  LinearTex(uint32_t W, uint32_t H) : w(W), h(H), rgb(size_t(W) * H * 3) {}
  void set(uint32_t x, uint32_t y, double r, double g, double b) {
    float* p = &rgb[(size_t(y) * w + x) * 3];
    p[0] = float(r);
    p[1] = float(g);
    p[2] = float(b);
  }
  Texture encode(const std::string& name) const {
    Texture t;
    t.name = name;
    t.width = w;
    t.height = h;
    t.rgba.resize(size_t(w) * h);
    for (size_t i = 0; i < t.rgba.size(); ++i) {
      uint32_t c[3];
      for (int k = 0; k < 3; ++k)
        c[k] = uint32_t(
            std::lround(std::clamp(io::linear_to_srgb(std::clamp(rgb[i * 3 + k], 0.f, 1.f)), 0.f, 1.f) * 255.f));
      t.rgba[i] = c[0] | c[1] << 8 | c[2] << 16 | 0xFF000000u;
    }
    return t;
  }
};

}  // namespace

// Paper with rows of glyph-like strokes (text): 5x7 cells of random bars, a large headline row.
Texture text_texture(uint32_t seed, double paper, double ink, const std::array<double, 3>& tint) {
  const uint32_t N = 512;
  LinearTex t(N, N);
  std::vector<uint8_t> mask(size_t(N) * N, 0);
  Rng rng{seed};
  auto glyph = [&](int x0, int y0, int scale) {
    // A glyph: a few strokes on a 5x7 grid.
    const int strokes = 2 + int(rng.uni() * 3);
    for (int s = 0; s < strokes; ++s) {
      const bool horiz = rng.uni() < 0.5;
      const int a = int(rng.uni() * (horiz ? 7 : 5)), b0 = int(rng.uni() * 3),
                len = 2 + int(rng.uni() * (horiz ? 3 : 5));
      for (int k = 0; k < len; ++k) {
        const int gx = horiz ? b0 + k : a, gy = horiz ? a : b0 + k;
        if (gx >= 5 || gy >= 7) continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int x = x0 + gx * scale + dx, y = y0 + gy * scale + dy;
            if (x >= 0 && y >= 0 && x < int(N) && y < int(N)) mask[size_t(y) * N + x] = 1;
          }
      }
    }
  };
  int y = 16;
  // Headline.
  for (int x = 24; x + 30 < int(N) - 24; x += 36) glyph(x, y, 5);
  y += 56;
  while (y + 16 < int(N) - 16) {
    int x = 24;
    while (x + 12 < int(N) - 24) {
      const int word = 2 + int(rng.uni() * 6);
      for (int k = 0; k < word && x + 12 < int(N) - 24; ++k, x += 14) glyph(x, y, 2);
      x += 12;
    }
    y += rng.uni() < 0.15 ? 34 : 20;
  }
  for (uint32_t yy = 0; yy < N; ++yy)
    for (uint32_t xx = 0; xx < N; ++xx) {
      const double grain = 0.9 + 0.1 * fbm(xx / double(N), yy / double(N), seed + 7, 8);
      const double v = (mask[size_t(yy) * N + xx] ? ink : paper) * grain;
      t.set(xx, yy, v * tint[0], v * tint[1], v * tint[2]);
    }
  return t.encode("text" + std::to_string(seed));
}

Texture checker_texture() {
  const uint32_t N = 512;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const int cx = x / 64, cy = y / 64;
      const double n = fbm(x / double(N), y / double(N), 11, 8);
      const bool dark = (cx + cy) & 1;
      double r = dark ? 0.06 : 0.55, g = dark ? 0.05 : 0.45, b = dark ? 0.04 : 0.3;
      const double k = 0.7 + 0.6 * n;
      // Fine wood-grain lines.
      const double grain = 0.85 + 0.15 * std::sin((y + 6 * n * 64) * 0.9);
      if (x % 64 == 0 || y % 64 == 0) r = g = b = 0.02;
      t.set(x, y, r * k * grain, g * k * grain, b * k * grain);
    }
  return t.encode("floor");
}

Texture brick_texture() {
  const uint32_t N = 512;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const int row = y / 32, shift = (row & 1) * 32;
      const int col = (x + shift) / 64;
      const bool mortar = (y % 32) < 3 || ((x + shift) % 64) < 3;
      const uint32_t h = hash2(col, row, 5);
      const double base = 0.35 + 0.3 * ((h & 0xFF) / 255.0);
      const double n = 0.75 + 0.5 * fbm(x / double(N), y / double(N), 3, 16);
      if (mortar)
        t.set(x, y, 0.8, 0.78, 0.72);
      else
        t.set(x, y, base * n, 0.35 * base * n, 0.25 * base * n);
    }
  return t.encode("brick");
}

Texture noise_texture(uint32_t seed) {
  const uint32_t N = 256;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const double u = x / double(N), v = y / double(N);
      const double a = fbm(u, v, seed, 4), b = fbm(u, v, seed + 100, 4), c = fbm(u, v, seed + 200, 8);
      const double spots = c > 0.62 ? 0.05 : 1.0;
      t.set(x, y, std::pow(a, 2.0) * spots, std::pow(b, 2.0) * spots * 0.9, 0.6 * c * c * spots);
    }
  return t.encode("noise" + std::to_string(seed));
}

Texture grating_texture() {
  const uint32_t N = 512;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const double u = x / double(N) - 0.5, v = y / double(N) - 0.5;
      const double r = std::sqrt(u * u + v * v);
      const double s = 0.5 + 0.5 * std::sin(2 * M_PI * (14 * r + 40 * r * r));
      const double band = (x / 128 + y / 128) & 1 ? 1.0 : 0.55;
      t.set(x, y, (0.03 + 0.9 * s) * band, (0.03 + 0.85 * s) * band, (0.05 + 0.7 * s));
    }
  return t.encode("grating");
}

Texture dark_texture() {
  const uint32_t N = 256;
  LinearTex t(N, N);
  for (uint32_t y = 0; y < N; ++y)
    for (uint32_t x = 0; x < N; ++x) {
      const double n = fbm(x / double(N), y / double(N), 21, 8);
      const bool weave = ((x / 4) + (y / 4)) & 1;
      const double v = 0.012 + 0.03 * n + (weave ? 0.01 : 0.0);
      t.set(x, y, v, v * 0.95, v * 1.2);
    }
  return t.encode("dark");
}

}  // namespace evflow::sim
