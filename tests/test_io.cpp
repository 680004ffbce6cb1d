// Dataset readers and writers (engine/io): round trips and malformed inputs.
#include <catch2/catch.hpp>

#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include "io/atomic_file.h"
#include "io/dataset.h"
#include "io/dataset_writer.h"
#include "io/events_h5.h"
#include "io/events_txt.h"
#include "io/image.h"
#include "io/image_codec.h"
#include "io/llff.h"
#include "io/npy.h"

namespace fs = std::filesystem;
using namespace evflow;
using namespace evflow::io;
using Catch::Contains;

namespace {

struct TmpDir {
  fs::path path;
  TmpDir() {
    static int counter = 0;
    path =
        fs::temp_directory_path() / ("evflow_test_io_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TmpDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  fs::path operator/(const std::string& s) const { return path / s; }
};

void write_text(const fs::path& p, const std::string& s) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  f << s;
}

std::string read_bytes(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
}

void truncate_file(const fs::path& p, double fraction) {
  fs::resize_file(p, static_cast<uintmax_t>(fs::file_size(p) * fraction));
}

Image random_image(uint32_t w, uint32_t h, uint32_t c, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  Image im(w, h, c);
  for (auto& v : im.data) v = u(rng);
  return im;
}

// Events on a microsecond grid, sorted, both polarities.
EventStream random_events(uint32_t w, uint32_t h, size_t n, uint32_t seed, int64_t t0_us = 1000) {
  std::mt19937 rng(seed);
  EventStream ev;
  ev.width = w;
  ev.height = h;
  int64_t t = t0_us;
  for (size_t i = 0; i < n; ++i) {
    t += rng() % 50;
    ev.push(uint16_t(rng() % w), uint16_t(rng() % h), double(t) / 1e6, (rng() & 1) ? 1 : -1);
  }
  return ev;
}

void require_same_events(const EventStream& a, const EventStream& b) {
  REQUIRE(a.size() == b.size());
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  REQUIRE(a.x == b.x);
  REQUIRE(a.y == b.y);
  REQUIRE(a.p == b.p);
  for (size_t i = 0; i < a.size(); ++i)
    if (a.t[i] != b.t[i]) FAIL("t[" << i << "] " << a.t[i] << " != " << b.t[i]);
}

template <typename T>
void npy_round_trip(const fs::path& p, std::vector<size_t> shape) {
  size_t n = 1;
  for (size_t s : shape) n *= s;
  std::vector<T> v(n);
  for (size_t i = 0; i < n; ++i) {
    if constexpr (std::is_floating_point_v<T>)
      v[i] = T(i) * T(0.37) - T(3.5);
    else if constexpr (std::is_signed_v<T>)
      v[i] = T(int(i % 200) - 100);
    else
      v[i] = T(i * 7 % 250);
  }
  write_npy(p, shape, v);
  NpyArray a = read_npy(p);
  REQUIRE(a.dtype == dtype_of<T>());
  REQUIRE(a.shape == shape);
  REQUIRE(a.template as<T>() == v);
  auto d = a.to_double();
  for (size_t i = 0; i < n; ++i) REQUIRE(d[i] == double(v[i]));
}

// Writes a raw HDF5 1-D dataset (test helper for foreign layouts).
template <typename T>
void h5_put(hid_t loc, const char* name, hid_t type, const std::vector<T>& v) {
  hsize_t n = v.size();
  hid_t s = H5Screate_simple(1, &n, nullptr);
  hid_t d = H5Dcreate2(loc, name, type, s, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  H5Dclose(d);
  H5Sclose(s);
}

}  // namespace

TEST_CASE("atomic writes leave the old file alone on failure", "[io]") {
  TmpDir dir;
  const fs::path p = dir / "a.txt";
  write_file_atomic(p, [](const fs::path& tmp) { write_text(tmp, "old"); });
  REQUIRE(read_bytes(p) == "old");
  REQUIRE_THROWS_WITH(write_file_atomic(p,
                                        [](const fs::path& tmp) {
                                          write_text(tmp, "half");
                                          throw std::runtime_error("boom");
                                        }),
                      "boom");
  REQUIRE(read_bytes(p) == "old");
  REQUIRE_THROWS_WITH(write_file_atomic(p, [](const fs::path&) {}), Contains("a.txt"));
  size_t files = 0;
  for (auto& e : fs::directory_iterator(dir.path)) {
    (void)e;
    ++files;
  }
  REQUIRE(files == 1);  // no temporaries left behind
}

TEST_CASE("npy round trips every dtype", "[io]") {
  TmpDir dir;
  npy_round_trip<float>(dir / "f4.npy", {3, 4});
  npy_round_trip<double>(dir / "f8.npy", {2, 3, 5});
  npy_round_trip<int8_t>(dir / "i1.npy", {7});
  npy_round_trip<int16_t>(dir / "i2.npy", {4, 4});
  npy_round_trip<int32_t>(dir / "i4.npy", {1, 9});
  npy_round_trip<int64_t>(dir / "i8.npy", {5, 1});
  npy_round_trip<uint8_t>(dir / "u1.npy", {300});
  npy_round_trip<uint16_t>(dir / "u2.npy", {2, 2, 2});
  npy_round_trip<uint32_t>(dir / "u4.npy", {6});
  npy_round_trip<uint64_t>(dir / "u8.npy", {3, 2});
  npy_round_trip<double>(dir / "scalar.npy", {});
  npy_round_trip<float>(dir / "empty.npy", {0, 3});
  std::vector<bool> b{true, false, true, true};
  write_npy(dir / "b1.npy", {4}, b);
  NpyArray a = read_npy(dir / "b1.npy");
  REQUIRE(a.dtype == DType::b1);
  REQUIRE(a.as<bool>() == b);
  REQUIRE(a.to_double() == std::vector<double>{1, 0, 1, 1});
  // header is padded to 64 bytes, as NumPy does
  std::string raw = read_bytes(dir / "f8.npy");
  REQUIRE((10 + (uint8_t(raw[8]) | (uint8_t(raw[9]) << 8))) % 64 == 0);

  SECTION("version 2 header written by hand") {
    std::string hdr = "{'descr': '<i2', 'fortran_order': False, 'shape': (3,), }";
    hdr.append((64 - (12 + hdr.size() + 1) % 64) % 64, ' ');
    hdr += '\n';
    std::string f = std::string("\x93NUMPY\x02\x00", 8);
    uint32_t len = uint32_t(hdr.size());
    f.append(reinterpret_cast<const char*>(&len), 4);
    f += hdr;
    int16_t v[3] = {-1, 2, 300};
    f.append(reinterpret_cast<const char*>(v), 6);
    write_text(dir / "v2.npy", f);
    std::vector<size_t> shape;
    REQUIRE(read_npy_double(dir / "v2.npy", &shape) == std::vector<double>{-1, 2, 300});
    REQUIRE(shape == std::vector<size_t>{3});
  }
}

TEST_CASE("npy rejects malformed files with the file name", "[io]") {
  TmpDir dir;
  std::vector<float> v(12, 1.f);
  write_npy(dir / "ok.npy", {3, 4}, v);
  const std::string good = read_bytes(dir / "ok.npy");

  fs::copy_file(dir / "ok.npy", dir / "trunc.npy");
  fs::resize_file(dir / "trunc.npy", good.size() - 5);
  REQUIRE_THROWS_WITH(read_npy(dir / "trunc.npy"), Contains("trunc.npy") && Contains("truncated"));

  write_text(dir / "extra.npy", good + "xxxx");
  REQUIRE_THROWS_WITH(read_npy(dir / "extra.npy"), Contains("extra.npy") && Contains("mismatch"));

  auto patched = [&](const std::string& from, const std::string& to, const char* name) {
    std::string s = good;
    size_t k = s.find(from);
    REQUIRE(k != std::string::npos);
    s.replace(k, from.size(), to);
    write_text(dir / name, s);
  };
  patched("False", "True ", "fortran.npy");
  REQUIRE_THROWS_WITH(read_npy(dir / "fortran.npy"), Contains("fortran.npy") && Contains("Fortran"));
  patched("<f4", ">f4", "big.npy");
  REQUIRE_THROWS_WITH(read_npy(dir / "big.npy"), Contains("big.npy") && Contains("big-endian"));
  patched("<f4", "<c8", "complex.npy");
  REQUIRE_THROWS_WITH(read_npy(dir / "complex.npy"), Contains("complex.npy") && Contains("unsupported"));
  patched("(3, 4)", "(3, 5)", "shape.npy");
  REQUIRE_THROWS_WITH(read_npy(dir / "shape.npy"), Contains("shape.npy"));
  write_text(dir / "magic.npy", "hello world, not numpy at all");
  REQUIRE_THROWS_WITH(read_npy(dir / "magic.npy"), Contains("magic.npy"));
  REQUIRE_THROWS_WITH(read_npy(dir / "missing.npy"), Contains("missing.npy"));
  REQUIRE_THROWS_WITH(read_npy(dir / "ok.npy").as<double>(), Contains("ok.npy") && Contains("<f4"));
}

TEST_CASE("images: PNG within 8-bit quantisation, EXR exact", "[io]") {
  TmpDir dir;
  Image im = random_image(17, 11, 3, 1);
  write_image(dir / "a.png", im);
  write_image(dir / "a.exr", im);
  Image png = read_image(dir / "a.png");
  Image exr = read_image(dir / "a.exr");
  REQUIRE(png.width == 17);
  REQUIRE(png.height == 11);
  REQUIRE(png.channels == 3);
  REQUIRE(exr.data == im.data);
  for (size_t i = 0; i < im.data.size(); ++i)
    REQUIRE(std::fabs(linear_to_srgb(png.data[i]) - linear_to_srgb(im.data[i])) <= 0.5f / 255.f + 1e-5f);
  // rewriting what was read gives the same 8-bit file content
  write_image(dir / "b.png", png);
  REQUIRE(read_image(dir / "b.png").data == png.data);

  // grey PNG reads as RGB
  Image grey = random_image(5, 4, 1, 2);
  write_image(dir / "g.png", grey);
  Image g = read_image(dir / "g.png");
  REQUIRE(g.channels == 3);
  REQUIRE(g.data[3] == g.data[4]);
  REQUIRE(std::fabs(g.data[3] - grey.data[1]) < 0.01f);

  REQUIRE(srgb_to_linear(linear_to_srgb(0.2f)) == Approx(0.2f).epsilon(1e-6));
  REQUIRE_THROWS_WITH(read_image(dir / "none.png"), Contains("none.png"));
  write_text(dir / "junk.png", "not a png");
  REQUIRE_THROWS_WITH(read_image(dir / "junk.png"), Contains("junk.png"));
  fs::copy_file(dir / "a.png", dir / "trunc.png");
  truncate_file(dir / "trunc.png", 0.5);
  REQUIRE_THROWS_WITH(read_image(dir / "trunc.png"), Contains("trunc.png"));
  REQUIRE_THROWS_WITH(write_image(dir / "a.bmp", im), Contains("a.bmp"));
}

// The stb codec (the whole codec of an EVFLOW_IMAGE_IO=stb build) against OpenImageIO's, on
// files each writes: the same values, and the same refusals naming the file.
#ifndef EVF_IMAGE_IO_STB
TEST_CASE("images: the stb codec reads and writes as OpenImageIO does", "[io]") {
  TmpDir dir;
  for (uint32_t c : {1u, 3u, 4u}) {
    std::vector<uint8_t> px(size_t(13) * 9 * c);
    std::mt19937 rng(c);
    for (auto& v : px) v = uint8_t(rng() & 255u);
    const std::string n = std::to_string(c);
    codec::oiio::encode(dir / ("o" + n + ".png"), dir / "o.png", 13, 9, c, false, px.data());
    codec::stb::encode(dir / ("s" + n + ".png"), dir / "s.png", 13, 9, c, false, px.data());
    for (const char* f : {"o", "s"}) {
      const fs::path p = dir / (f + n + ".png");
      const codec::Decoded a = codec::oiio::decode(p), b = codec::stb::decode(p);
      REQUIRE(b.width == 13);
      REQUIRE(b.height == 9);
      REQUIRE(b.channels == int(c));
      REQUIRE(b.eight_bit);
      REQUIRE_FALSE(b.is_float);
      REQUIRE(a.values == b.values);  // with alpha too: colour as stored, not times alpha
      for (size_t i = 0; i < px.size(); ++i) REQUIRE(b.values[i] == Approx(px[i] / 255.f).margin(1e-7));
    }
  }
  // JPEG: lossy, so each codec's file decoded by both agrees within a level.
  std::vector<uint8_t> smooth(size_t(16) * 16 * 3);
  for (size_t i = 0; i < smooth.size(); ++i) smooth[i] = uint8_t(64 + (i / 3) % 16 * 4);
  codec::stb::encode(dir / "s.jpg", dir / "s.jpg", 16, 16, 3, false, smooth.data());
  const codec::Decoded ja = codec::oiio::decode(dir / "s.jpg"), jb = codec::stb::decode(dir / "s.jpg");
  REQUIRE(ja.values.size() == jb.values.size());
  for (size_t i = 0; i < ja.values.size(); ++i) REQUIRE(std::fabs(ja.values[i] - jb.values[i]) <= 1.5f / 255.f);

  // Refusals name the file: EXR, other extensions, a truncated or foreign file.
  const float f[3] = {0.1f, 0.2f, 0.3f};
  REQUIRE_THROWS_WITH(codec::stb::encode(dir / "x.exr", dir / "x.exr", 1, 1, 3, true, f),
                      Contains("x.exr") && Contains("OpenImageIO"));
  REQUIRE_THROWS_WITH(codec::stb::encode(dir / "x.bmp", dir / "x.bmp", 1, 1, 3, false, smooth.data()),
                      Contains("x.bmp"));
  write_exr(dir / "y.exr", Image(2, 2, 3, 0.5f));
  REQUIRE_THROWS_WITH(codec::stb::decode(dir / "y.exr"), Contains("y.exr") && Contains("OpenImageIO"));
  fs::copy_file(dir / "o3.png", dir / "trunc.png");
  truncate_file(dir / "trunc.png", 0.5);
  REQUIRE_THROWS_WITH(codec::stb::decode(dir / "trunc.png"), Contains("trunc.png"));
  write_text(dir / "junk.png", "not a png");
  REQUIRE_THROWS_WITH(codec::stb::decode(dir / "junk.png"), Contains("junk.png"));
}
#endif

TEST_CASE("LLFF poses_bounds: exact rows, OpenCV cameras", "[io]") {
  TmpDir dir;
  SECTION("axis convention") {
    // A camera at (1, 2, 3) looking down world -z with world +y up (down = -y, right = +x, back = +z).
    LlffRow r{0,   1, 0, 1, 260,  //
              -1,  0, 0, 2, 346,  //
              0,   0, 1, 3, 300,  //
              0.5, 20};
    Camera c = llff_row_to_camera(r);
    REQUIRE(c.width == 346);
    REQUIRE(c.height == 260);
    REQUIRE(c.fx == 300);
    REQUIRE(c.fy == 300);
    REQUIRE(c.cx == 173);
    REQUIRE(c.cy == 130);
    auto cam = [&](double x, double y, double z) {
      std::array<double, 3> p{};
      for (int i = 0; i < 3; ++i) p[i] = c.R[i * 3] * x + c.R[i * 3 + 1] * y + c.R[i * 3 + 2] * z + c.t[i];
      return p;
    };
    auto ahead = cam(1, 2, -2);  // 5 in front
    REQUIRE(ahead[0] == Approx(0).margin(1e-12));
    REQUIRE(ahead[1] == Approx(0).margin(1e-12));
    REQUIRE(ahead[2] == Approx(5));
    REQUIRE(cam(2, 2, -2)[0] > 0);  // world +x is image right
    REQUIRE(cam(1, 3, -2)[1] < 0);  // world +y is image up (OpenCV y points down)
    auto ctr = c.center();
    REQUIRE(ctr[0] == Approx(1));
    REQUIRE(ctr[1] == Approx(2));
    REQUIRE(ctr[2] == Approx(3));
    LlffRow back = camera_to_llff_row(c, 0.5, 20);
    REQUIRE(back == r);  // signed-permutation rotation, integer centre: exact
  }
  SECTION("file round trip is bit exact") {
    std::vector<LlffRow> rows;
    std::mt19937 rng(3);
    std::normal_distribution<double> n(0, 1);
    for (int k = 0; k < 5; ++k) {
      Camera c = Camera::look_at(64, 48, 40 + k, {n(rng), n(rng), 3 + n(rng)}, {0, 0, 0});
      rows.push_back(camera_to_llff_row(c, 0.1 * (k + 1), 10.0 + k));
      Camera back = llff_row_to_camera(rows.back());
      for (int i = 0; i < 9; ++i) REQUIRE(back.R[i] == c.R[i]);
      for (int i = 0; i < 3; ++i) REQUIRE(back.t[i] == Approx(c.t[i]).margin(1e-14));
      REQUIRE(back.fx == c.fx);
      REQUIRE(back.width == 64);
    }
    write_poses_bounds(dir / "poses_bounds.npy", rows);
    PosesBounds pb = read_poses_bounds(dir / "poses_bounds.npy");
    REQUIRE(pb.rows == rows);
    REQUIRE(pb.near[2] == 0.1 * 3);
    REQUIRE(pb.far[4] == 14.0);
    write_poses_bounds(dir / "again.npy", pb.rows);
    REQUIRE(read_bytes(dir / "again.npy") == read_bytes(dir / "poses_bounds.npy"));
  }
  SECTION("malformed") {
    write_npy(dir / "p16.npy", {2, 16}, std::vector<double>(32, 1.0));
    REQUIRE_THROWS_WITH(read_poses_bounds(dir / "p16.npy"), Contains("p16.npy") && Contains("N x 17"));
    write_npy(dir / "pint.npy", {1, 17}, std::vector<int32_t>(17, 1));
    REQUIRE_THROWS_WITH(read_poses_bounds(dir / "pint.npy"), Contains("pint.npy") && Contains("float64"));
    write_npy(dir / "phwf.npy", {1, 17}, std::vector<double>(17, 0.0));
    REQUIRE_THROWS_WITH(read_poses_bounds(dir / "phwf.npy"), Contains("phwf.npy") && Contains("(h, w, f)"));
    REQUIRE_THROWS_WITH(read_poses_bounds(dir / "nope.npy"), Contains("nope.npy"));
  }
}

TEST_CASE("HDF5 events: DSEC style round trip and foreign layouts", "[io]") {
  TmpDir dir;
  EventStream ev = random_events(64, 48, 5000, 7);
  const std::vector<double> es{0.001, 0.05}, ee{0.02, 0.09};
  H5WriteOptions wo;
  wo.t_offset_us = 1000;
  write_events_h5(dir / "ev.h5", ev, es, ee, wo);
  H5Events r = read_events_h5(dir / "ev.h5");
  require_same_events(r.events, ev);
  REQUIRE(r.t_offset_us == 1000);
  REQUIRE(r.exposure_start == es);
  REQUIRE(r.exposure_end == ee);
  H5ReadOptions raw;
  raw.apply_t_offset = false;
  REQUIRE(read_events_h5(dir / "ev.h5", raw).events.t[0] == Approx(ev.t[0] - 0.001).margin(1e-12));

  SECTION("empty stream") {
    EventStream e0;
    e0.width = 8;
    e0.height = 4;
    write_events_h5(dir / "e0.h5", e0);
    H5Events z = read_events_h5(dir / "e0.h5");
    REQUIRE(z.events.size() == 0);
    REQUIRE(z.events.width == 8);
  }
  SECTION("root-level x, y, t, p (EvDeblurNeRF): float ns times, int16 coordinates, -1/1 polarity") {
    hid_t f = H5Fcreate((dir / "root.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    h5_put(f, "x", H5T_NATIVE_INT16, std::vector<int16_t>{1, 2, 3});
    h5_put(f, "y", H5T_NATIVE_INT16, std::vector<int16_t>{0, 5, 1});
    h5_put(f, "t", H5T_NATIVE_DOUBLE, std::vector<double>{1e9, 1.5e9, 2e9});
    h5_put(f, "p", H5T_NATIVE_INT8, std::vector<int8_t>{-1, 1, 1});
    H5Fclose(f);
    H5ReadOptions o;
    o.unit = TimeUnit::ns;
    o.width = 10;
    o.height = 10;
    H5Events e = read_events_h5(dir / "root.h5", o);
    REQUIRE(e.events.size() == 3);
    REQUIRE(e.events.t == std::vector<double>{1.0, 1.5, 2.0});
    REQUIRE(e.events.p == std::vector<int8_t>{-1, 1, 1});
    REQUIRE(e.events.y[1] == 5);
    // int64 ns times
    f = H5Fcreate((dir / "root_ns.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    h5_put(f, "x", H5T_NATIVE_UINT16, std::vector<uint16_t>{1, 2});
    h5_put(f, "y", H5T_NATIVE_UINT16, std::vector<uint16_t>{0, 5});
    h5_put(f, "t", H5T_NATIVE_INT64, std::vector<int64_t>{123456789, 223456789});
    h5_put(f, "p", H5T_NATIVE_UINT8, std::vector<uint8_t>{0, 1});
    H5Fclose(f);
    e = read_events_h5(dir / "root_ns.h5", o);
    REQUIRE(e.events.t[0] == 0.123456789);
    REQUIRE(e.events.width == 10);
  }
  SECTION("Blosc-compressed DSEC file (needs hdf5-filter-plugin-blosc-serial)") {
    if (!h5_blosc_available()) {
      FAIL(
          "the Blosc HDF5 plugin is not available: install hdf5-filter-plugin-blosc-serial "
          "(scripts/install-deps.sh does)");
    }
    hid_t f = H5Fcreate((dir / "blosc.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    hid_t g = H5Gcreate2(f, "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    hsize_t n = ev.size(), chunk = 1024;
    hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_chunk(dcpl, 1, &chunk);
    unsigned cd[7] = {2, 2, 0, 0, 5, 1, 5};  // level 5, shuffle, zstd
    REQUIRE(H5Pset_filter(dcpl, 32001, H5Z_FLAG_OPTIONAL, 7, cd) >= 0);
    auto put = [&](const char* name, hid_t type, const void* data) {
      hid_t s = H5Screate_simple(1, &n, nullptr);
      hid_t d = H5Dcreate2(g, name, type, s, H5P_DEFAULT, dcpl, H5P_DEFAULT);
      REQUIRE(d >= 0);
      REQUIRE(H5Dwrite(d, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) >= 0);
      H5Dclose(d);
      H5Sclose(s);
    };
    std::vector<int64_t> t(n);
    std::vector<uint8_t> p(n);
    for (size_t i = 0; i < n; ++i) {
      t[i] = std::llround(ev.t[i] * 1e6);
      p[i] = ev.p[i] > 0;
    }
    put("x", H5T_NATIVE_UINT16, ev.x.data());
    put("y", H5T_NATIVE_UINT16, ev.y.data());
    put("t", H5T_NATIVE_INT64, t.data());
    put("p", H5T_NATIVE_UINT8, p.data());
    H5Pclose(dcpl);
    H5Gclose(g);
    H5Fclose(f);
    H5ReadOptions o;
    o.width = 64;
    o.height = 48;
    require_same_events(read_events_h5(dir / "blosc.h5", o).events, ev);
  }
  SECTION("malformed inputs name the file") {
    H5ReadOptions small;
    small.width = 32;  // events reach x = 63
    small.height = 48;
    REQUIRE_THROWS_WITH(read_events_h5(dir / "ev.h5", small), Contains("ev.h5") && Contains("outside"));

    EventStream uns = ev;
    hid_t f = H5Fcreate((dir / "unsorted.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    h5_put(f, "x", H5T_NATIVE_UINT16, std::vector<uint16_t>{1, 2, 3});
    h5_put(f, "y", H5T_NATIVE_UINT16, std::vector<uint16_t>{1, 2, 3});
    h5_put(f, "t", H5T_NATIVE_INT64, std::vector<int64_t>{10, 30, 20});
    h5_put(f, "p", H5T_NATIVE_UINT8, std::vector<uint8_t>{1, 0, 1});
    H5Fclose(f);
    REQUIRE_THROWS_WITH(read_events_h5(dir / "unsorted.h5"), Contains("unsorted.h5") && Contains("sorted"));

    f = H5Fcreate((dir / "count.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    hid_t g = H5Gcreate2(f, "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    h5_put(g, "x", H5T_NATIVE_UINT16, std::vector<uint16_t>{1, 2, 3});
    h5_put(g, "y", H5T_NATIVE_UINT16, std::vector<uint16_t>{1, 2});
    h5_put(g, "t", H5T_NATIVE_INT64, std::vector<int64_t>{10, 20, 30});
    h5_put(g, "p", H5T_NATIVE_UINT8, std::vector<uint8_t>{1, 0, 1});
    H5Gclose(g);
    H5Fclose(f);
    REQUIRE_THROWS_WITH(read_events_h5(dir / "count.h5"), Contains("count.h5") && Contains("differ in length"));

    f = H5Fcreate((dir / "nop.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    h5_put(f, "x", H5T_NATIVE_UINT16, std::vector<uint16_t>{1});
    H5Fclose(f);
    REQUIRE_THROWS_WITH(read_events_h5(dir / "nop.h5"), Contains("nop.h5") && Contains("/y"));

    fs::copy_file(dir / "ev.h5", dir / "trunc.h5");
    truncate_file(dir / "trunc.h5", 0.6);
    REQUIRE_THROWS_WITH(read_events_h5(dir / "trunc.h5"), Contains("trunc.h5"));
    write_text(dir / "text.h5", "definitely not hdf5");
    REQUIRE_THROWS_WITH(read_events_h5(dir / "text.h5"), Contains("text.h5"));
    REQUIRE_THROWS_WITH(read_events_h5(dir / "missing.h5"), Contains("missing.h5"));
    EventStream bad = ev;
    bad.x[3] = 200;
    REQUIRE_THROWS_WITH(write_events_h5(dir / "bad.h5", bad), Contains("bad.h5"));
    REQUIRE(!fs::exists(dir / "bad.h5"));
  }
}

TEST_CASE("text events: every time unit and polarity coding round trips exactly", "[io]") {
  TmpDir dir;
  EventStream ev = random_events(40, 30, 2000, 11, 123456);
  ev.t[5] = ev.t[4];  // ties are fine
  for (TimeUnit u : {TimeUnit::s, TimeUnit::ms, TimeUnit::us, TimeUnit::ns}) {
    for (PolarityCoding pc :
         {PolarityCoding::zero_one, PolarityCoding::minus_one_one, PolarityCoding::one_else_negative}) {
      const fs::path p = dir / ("ev_" + to_string(u) + ".txt");
      TxtWriteOptions wo;
      wo.unit = u;
      wo.polarity = pc;
      write_events_txt(p, ev, wo);
      TxtReadOptions ro;
      ro.unit = u;
      ro.polarity = pc;
      INFO("unit " << to_string(u));
      require_same_events(read_events_txt(p, ro), ev);
    }
  }
  // irregular (non-grid) times still round trip in every unit
  EventStream odd = ev;
  for (size_t i = 0; i < odd.size(); ++i) odd.t[i] = 0.1 + i * 1.2345678901234e-5;
  for (TimeUnit u : {TimeUnit::s, TimeUnit::ms, TimeUnit::us, TimeUnit::ns}) {
    TxtWriteOptions wo;
    wo.unit = u;
    write_events_txt(dir / "odd.txt", odd, wo);
    TxtReadOptions ro;
    ro.unit = u;
    require_same_events(read_events_txt(dir / "odd.txt", ro), odd);
  }
  SECTION("rpg style: header, seconds, comments, no header -> size from max") {
    write_text(dir / "rpg.txt",
               "# comment\n240 180\n0.000000000 33 39 1\n0.000011001 158 145 1\n0.000050999 88 143 0\n");
    EventStream r = read_events_txt(dir / "rpg.txt");
    REQUIRE(r.width == 240);
    REQUIRE(r.height == 180);
    REQUIRE(r.t[1] == 0.000011001);
    REQUIRE(r.p == std::vector<int8_t>{1, 1, -1});
    write_text(dir / "nohdr.txt", "1 3 4 1\n2 5 1 0\n");
    EventStream n = read_events_txt(dir / "nohdr.txt");
    REQUIRE(n.width == 6);
    REQUIRE(n.height == 5);
    REQUIRE(n.t == std::vector<double>{1, 2});
  }
  SECTION("malformed lines name the file and the line") {
    write_text(dir / "garbage.txt", "10 10\n0.1 1 1 1\n0.2 1 x 1\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "garbage.txt"), Contains("garbage.txt:3") && Contains("y coordinate"));
    write_text(dir / "fields.txt", "0.1 1 1 1\nhello\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "fields.txt"), Contains("fields.txt:2"));
    write_text(dir / "pol.txt", "0.1 1 1 1\n0.2 1 1 2\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "pol.txt"), Contains("pol.txt:2") && Contains("polarity"));
    TxtReadOptions pm;
    pm.polarity = PolarityCoding::minus_one_one;
    write_text(dir / "pm.txt", "0.1 1 1 1\n0.2 1 1 0\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "pm.txt", pm), Contains("pm.txt:2"));
    write_text(dir / "neg.txt", "0.1 -1 1 1\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "neg.txt"), Contains("neg.txt:1"));
    write_text(dir / "uns.txt", "0.2 1 1 1\n0.1 1 1 1\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "uns.txt"), Contains("uns.txt") && Contains("sorted"));
    write_text(dir / "out.txt", "4 4\n0.1 4 1 1\n");
    REQUIRE_THROWS_WITH(read_events_txt(dir / "out.txt"), Contains("out.txt") && Contains("outside"));
    REQUIRE_THROWS_WITH(read_events_txt(dir / "none.txt"), Contains("none.txt"));
  }
}

namespace {

Dataset make_dataset(uint32_t W, uint32_t H) {
  Dataset ds;
  for (int i = 0; i < 3; ++i) {
    View v;
    v.name = "view_" + std::to_string(i);
    v.blurry = random_image(W, H, 3, 100 + i);
    if (i != 1) v.sharp_mid = random_image(W, H, 3, 200 + i);
    v.camera = Camera::look_at(W, H, 50, {std::cos(i * 0.5), 0.2 * i, 3.0}, {0, 0, 0});
    v.camera.fy = v.camera.fx * 1.01;  // non-LLFF intrinsics survive through the manifest
    v.camera.cx += 0.25;
    v.exposure_start = 0.01 + 0.1 * i;
    v.exposure_end = v.exposure_start + 0.0333;
    ds.train.push_back(v);
  }
  for (int i = 0; i < 2; ++i) {
    View v;
    v.name = "novel_" + std::to_string(i);
    v.sharp_mid = random_image(W, H, 3, 300 + i);
    v.camera = Camera::look_at(W, H, 50, {-1.0 * i, 0.5, 3.0}, {0, 0, 0});
    ds.novel.push_back(v);
  }
  ds.events = random_events(W, H, 3000, 5);
  ds.near = 0.5;
  ds.far = 12.0;
  ds.manifest = {{"events_sim", {{"threshold_pos", 0.2}, {"threshold_neg", 0.3}, {"sigma", 0.03}}},
                 {"noise", {{"shot_hz", 1.0}}},
                 {"seed", 1234}};
  return ds;
}

void require_same_camera(const Camera& a, const Camera& b) {
  REQUIRE(a.width == b.width);
  REQUIRE(a.height == b.height);
  REQUIRE(a.fx == b.fx);
  REQUIRE(a.fy == b.fy);
  REQUIRE(a.cx == b.cx);
  REQUIRE(a.cy == b.cy);
  REQUIRE(a.R == b.R);
  for (int i = 0; i < 3; ++i) REQUIRE(a.t[i] == Approx(b.t[i]).margin(1e-14));
}

void write_jpg(const fs::path& p, const Image& im) {
  fs::create_directories(p.parent_path());
  std::vector<uint8_t> px(im.data.size());
  for (size_t i = 0; i < px.size(); ++i) px[i] = uint8_t(std::lround(linear_to_srgb(im.data[i]) * 255.f));
  evflow::io::codec::active::encode(p, p, im.width, im.height, 3, false, px.data());
}

}  // namespace

TEST_CASE("datasets in our layout round trip", "[io]") {
  TmpDir dir;
  Dataset ds = make_dataset(24, 16);
  WriteOptions exr;
  exr.image_ext = ".exr";
  write_evflow_dataset(ds, dir / "exr", exr);
  Dataset r = load_dataset(dir / "exr");
  REQUIRE(r.layout == "evflow");
  REQUIRE(r.train.size() == 3);
  REQUIRE(r.novel.size() == 2);
  for (size_t i = 0; i < 3; ++i) {
    REQUIRE(r.train[i].name == ds.train[i].name);
    REQUIRE(r.train[i].blurry.data == ds.train[i].blurry.data);
    REQUIRE(r.train[i].sharp_mid.has_value() == ds.train[i].sharp_mid.has_value());
    if (ds.train[i].sharp_mid) REQUIRE(r.train[i].sharp_mid->data == ds.train[i].sharp_mid->data);
    REQUIRE(r.train[i].exposure_start == ds.train[i].exposure_start);
    REQUIRE(r.train[i].exposure_end == ds.train[i].exposure_end);
    require_same_camera(r.train[i].camera, ds.train[i].camera);
  }
  for (size_t i = 0; i < 2; ++i) {
    REQUIRE(r.novel[i].sharp_mid->data == ds.novel[i].sharp_mid->data);
    require_same_camera(r.novel[i].camera, ds.novel[i].camera);
  }
  require_same_events(r.events, ds.events);
  REQUIRE(r.near == 0.5);
  REQUIRE(r.far == 12.0);
  REQUIRE(r.manifest["seed"] == 1234);
  REQUIRE(r.manifest["events_sim"]["threshold_neg"] == 0.3);
  REQUIRE(fs::exists(dir / "exr/images_gt_blur/view_0.exr"));
  REQUIRE(!fs::exists(dir / "exr/images_gt_blur/view_1.exr"));

  // PNG (the default) within quantisation; writing what was read is stable
  write_evflow_dataset(r, dir / "png");
  Dataset q = load_dataset(dir / "png");
  for (size_t i = 0; i < q.train[0].blurry.data.size(); ++i)
    REQUIRE(std::fabs(linear_to_srgb(q.train[0].blurry.data[i]) - linear_to_srgb(ds.train[0].blurry.data[i])) <=
            0.5f / 255.f + 1e-5f);
  require_same_events(q.events, ds.events);
  REQUIRE(q.manifest["seed"] == 1234);
  for (const char* f :
       {"dataset.json", "poses_bounds.npy", "events.h5", "images/view_2.png", "images_gt_novel/novel_1.png"})
    REQUIRE(fs::exists(dir / "png" / f));
  REQUIRE(read_poses_bounds(dir / "png/poses_bounds.npy").rows.size() == 5);

  SECTION("malformed datasets name the file") {
    const fs::path d = dir / "exr";
    fs::rename(d / "images/view_1.exr", d / "view_1.exr");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("view_1.exr") && Contains("missing"));
    fs::rename(d / "view_1.exr", d / "images/view_1.exr");

    write_image(d / "images/view_2.exr", random_image(23, 16, 3, 9));
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("view_2.exr") && Contains("size"));
    write_image(d / "images/view_2.exr", ds.train[2].blurry);

    fs::copy_file(d / "poses_bounds.npy", dir / "poses.bak");
    auto four = read_poses_bounds(dir / "poses.bak").cameras;
    four.pop_back();
    write_poses_bounds(d / "poses_bounds.npy", four, {1, 1, 1, 1}, {2, 2, 2, 2});
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("poses_bounds.npy") && Contains("4 poses"));
    truncate_file(d / "poses_bounds.npy", 0.7);
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("poses_bounds.npy") && Contains("truncated"));
    fs::copy_file(dir / "poses.bak", d / "poses_bounds.npy", fs::copy_options::overwrite_existing);

    truncate_file(d / "events.h5", 0.5);
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("events.h5"));
    fs::remove(d / "events.h5");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("events.h5") && Contains("missing"));

    std::string js = read_bytes(d / "dataset.json");
    write_text(d / "dataset.json", js.substr(0, js.size() / 2));
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("dataset.json"));
    REQUIRE_THROWS_WITH(load_dataset(dir / "nowhere"), Contains("nowhere"));
    fs::create_directories(dir / "empty");
    REQUIRE_THROWS_WITH(load_dataset(dir / "empty"), Contains("empty") && Contains("layout"));
  }
}

TEST_CASE("E3NeRF Real-World-Challenge folders", "[io]") {
  TmpDir dir;
  const uint32_t W = 34, H = 26;  // a tenth of 346 x 260
  const fs::path d = dir / "e3";
  std::vector<LlffRow> rows;
  for (int i = 0; i < 5; ++i) {
    // poses_bounds at full resolution 346 x 260: intrinsics are scaled to the images
    Camera c = Camera::look_at(346, 260, 40, {0.3 * i, 0.1, 2.5}, {0, 0, 0});
    rows.push_back(camera_to_llff_row(c, 0.2, 8.0));
  }
  write_poses_bounds(d / "poses_bounds.npy", rows);
  EventStream all;
  all.width = W;
  all.height = H;
  for (int v = 0; v < 3; ++v) {
    char name[8];
    std::snprintf(name, sizeof name, "%03d", v);
    write_jpg(d / "images" / (std::string(name) + ".jpg"), random_image(W, H, 3, 40 + v));
    std::string txt;
    for (int k = 0; k < 20; ++k) {
      const double t = 1.5 + v * 0.1 + k * 0.001;
      const int x = (k * 7 + v) % W, y = (k * 3) % H, p = k % 3 == 0 ? 1 : 0;
      char line[96];
      std::snprintf(line, sizeof line, "%.6f %d %d %d\n", t, x, y, p);
      txt += line;
      all.push(uint16_t(x), uint16_t(y), std::stod(std::string(line).substr(0, std::string(line).find(' '))),
               p == 1 ? 1 : -1);
    }
    write_text(d / "events" / (std::string(name) + ".txt"), txt);
  }
  for (int g = 0; g < 2; ++g) write_jpg(d / "gt" / ("00" + std::to_string(g) + ".jpg"), random_image(W, H, 3, 60 + g));

  Dataset ds = load_dataset(d);
  REQUIRE(ds.layout == "e3nerf");
  REQUIRE(ds.train.size() == 3);
  REQUIRE(ds.novel.size() == 2);
  REQUIRE(ds.train[1].name == "001");
  REQUIRE(ds.train[1].exposure_start == 1.6);
  REQUIRE(ds.train[1].exposure_end == Approx(1.619));
  REQUIRE(ds.train[0].camera.width == W);
  REQUIRE(ds.train[0].camera.fx == Approx(llff_row_to_camera(rows[0]).fx * W / 346.0));
  REQUIRE(ds.novel[1].camera.R == llff_row_to_camera(rows[4]).R);
  REQUIRE(ds.novel[0].sharp_mid->width == W);
  REQUIRE(ds.manifest["event_time_unit"] == "s");
  REQUIRE(ds.near == 0.2);
  require_same_events(ds.events, all);

  // and it can be saved in our layout
  write_evflow_dataset(ds, dir / "ours");
  Dataset o = load_dataset(dir / "ours");
  REQUIRE(o.train.size() == 3);
  require_same_events(o.events, all);

  SECTION("malformed") {
    write_text(d / "events/001.txt", "1.6 1 1 1\n1.7 999 1 1\n");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("001.txt") && Contains("outside"));
    write_text(d / "events/001.txt", "1.6 1 1 1\n1.5 1 1 1\n");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("001.txt") && Contains("sorted"));
    write_text(d / "events/001.txt", "1.6 1 1 1\n1.7 1 one 1\n");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("001.txt:2"));
    fs::remove(d / "events/001.txt");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("001.txt") && Contains("missing"));
    write_text(d / "events/001.txt", "1.6 1 1 1\n");
    write_jpg(d / "gt/002.jpg", random_image(W, H, 3, 1));
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("poses_bounds.npy") && Contains("5 poses"));
    fs::remove(d / "gt/002.jpg");
    write_jpg(d / "gt/001.jpg", random_image(W + 3, H, 3, 1));
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("001.jpg") && Contains("size"));
  }
}

TEST_CASE("EBAD-NeRF folders: every 8th view is a test view", "[io]") {
  TmpDir dir;
  const uint32_t W = 12, H = 8;
  const size_t N = 10, bins = 4;  // test views: 0 and 8
  const fs::path d = dir / "ebad";
  std::vector<LlffRow> rows;
  for (size_t i = 0; i < N; ++i)
    rows.push_back(camera_to_llff_row(Camera::look_at(W, H, 45, {0.1 * i, 0, 3}, {0, 0, 0}), 0.3, 5.0 + i));
  write_poses_bounds(d / "poses_bounds.npy", rows);
  for (size_t i = 0; i < N; ++i) {
    char name[16];
    std::snprintf(name, sizeof name, "r_%02zu.png", i);
    write_image(d / "images" / name, random_image(W, H, 3, uint32_t(i)));
    if (i % 8)
      write_image(d / "images_gt_blur" / name, random_image(W, H, 3, uint32_t(100 + i)));
    else
      write_image(d / "images_gt_novel" / name, random_image(W, H, 3, uint32_t(200 + i)));
  }
  std::vector<float> counts(N * bins * W * H);
  for (size_t i = 0; i < counts.size(); ++i) counts[i] = float(int(i % 7) - 3);
  write_npy(d / "events.npy", {N, bins, size_t(W) * H}, counts);

  Dataset ds = load_dataset(d);
  REQUIRE(ds.layout == "ebad");
  REQUIRE(ds.train.size() == 8);
  REQUIRE(ds.novel.size() == 2);
  REQUIRE(ds.train[0].name == "r_01");
  REQUIRE(ds.novel[1].name == "r_08");
  REQUIRE(ds.train[0].camera.R == llff_row_to_camera(rows[1]).R);
  REQUIRE(ds.event_counts_shape == std::vector<size_t>{8, bins, size_t(W) * H});
  const size_t per = bins * W * H;
  // train row 7 is view 9
  REQUIRE(std::equal(ds.event_counts.begin() + 7 * per, ds.event_counts.end(), counts.begin() + 9 * per));
  REQUIRE(ds.train[0].sharp_mid.has_value());
  REQUIRE(ds.far == 5.0 + N - 1);

  // counts given for training views only, as int16
  std::vector<int16_t> c16(8 * per, -2);
  write_npy(d / "events.npy", {8, bins, size_t(W) * H}, c16);
  REQUIRE(load_dataset(d).event_counts[5] == -2.f);

  // our layout keeps the counts
  write_evflow_dataset(ds, dir / "ours");
  Dataset o = load_dataset(dir / "ours");
  REQUIRE(o.event_counts == ds.event_counts);
  REQUIRE(o.event_counts_shape == ds.event_counts_shape);

  SECTION("malformed") {
    write_npy(d / "events.npy", {N, bins, size_t(W) * H + 1}, std::vector<float>(N * bins * (W * H + 1)));
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("events.npy") && Contains("pixels"));
    write_npy(d / "events.npy", {3, bins, size_t(W) * H}, std::vector<float>(3 * per));
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("events.npy") && Contains("3 views"));
    fs::remove(d / "images/r_03.png");
    REQUIRE_THROWS_WITH(load_dataset(d), Contains("images") && Contains("9 images"));
  }
}
