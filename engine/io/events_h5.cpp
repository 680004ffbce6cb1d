#include "io/events_h5.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "io/atomic_file.h"

namespace evflow::io {

namespace fs = std::filesystem;

namespace {

constexpr H5Z_filter_t kBloscFilter = 32001;

// Turns HDF5's automatic error-stack printing off for the scope.
class QuietHdf5 {
 public:
  QuietHdf5() {
    H5Eget_auto2(H5E_DEFAULT, &func_, &data_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5() { H5Eset_auto2(H5E_DEFAULT, func_, data_); }
  QuietHdf5(const QuietHdf5&) = delete;
  QuietHdf5& operator=(const QuietHdf5&) = delete;

 private:
  H5E_auto2_t func_ = nullptr;
  void* data_ = nullptr;
};

class Hid {
 public:
  Hid() = default;
  Hid(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Hid(Hid&& o) noexcept : id_(o.id_), close_(o.close_) { o.id_ = -1; }
  Hid& operator=(Hid&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = o.id_;
      close_ = o.close_;
      o.id_ = -1;
    }
    return *this;
  }
  ~Hid() { reset(); }
  void reset() {
    if (id_ >= 0 && close_) close_(id_);
    id_ = -1;
  }
  hid_t get() const { return id_; }
  bool ok() const { return id_ >= 0; }

 private:
  hid_t id_ = -1;
  herr_t (*close_)(hid_t) = nullptr;
};

// Most recent HDF5 error description (major/minor of the innermost entry).
std::string h5_last_error() {
  std::string msg;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* e, void* d) -> herr_t {
        auto* m = static_cast<std::string*>(d);
        if (n == 0 && e->desc && *e->desc) *m = e->desc;
        return 0;
      },
      &msg);
  return msg;
}

[[noreturn]] void fail(const fs::path& path, const std::string& what) {
  throw std::runtime_error(path.string() + ": " + what);
}

bool link_exists(hid_t loc, const char* name) { return H5Lexists(loc, name, H5P_DEFAULT) > 0; }

// Describes filters of `dset` that this HDF5 cannot use ("" when all are available).
std::string missing_filters(hid_t dset) {
  Hid dcpl(H5Dget_create_plist(dset), H5Pclose);
  if (!dcpl.ok()) return "";
  std::string out;
  int nf = H5Pget_nfilters(dcpl.get());
  for (int i = 0; i < nf; ++i) {
    unsigned flags = 0, conf = 0;
    size_t ncd = 0;
    char name[256] = {0};
    H5Z_filter_t id = H5Pget_filter2(dcpl.get(), unsigned(i), &flags, &ncd, nullptr, sizeof name, name, &conf);
    if (id < 0 || H5Zfilter_avail(id) > 0) continue;
    out += "the data is compressed with HDF5 filter " + std::to_string(id) +
           (name[0] ? std::string(" (") + name + ")" : "") + ", which is not available";
    if (id == kBloscFilter)
      out +=
          ": install Debian's hdf5-filter-plugin-blosc-serial (or set HDF5_PLUGIN_PATH to a folder with the "
          "Blosc HDF5 plugin)";
    else
      out += ": install its HDF5 filter plugin (HDF5_PLUGIN_PATH)";
  }
  return out;
}

struct Dataset1D {
  Hid id;
  size_t n = 0;
  H5T_class_t cls = H5T_NO_CLASS;
  std::string name;
};

// HDF5 1.10 reads past a compact dataset's storage when the dataspace claims more values than
// the storage holds (a corrupt file): refuse such a dataset before reading it.
void check_compact_storage(const fs::path& path, hid_t dset, const std::string& name, size_t n, hid_t type) {
  Hid dcpl(H5Dget_create_plist(dset), H5Pclose);
  if (!dcpl.ok()) fail(path, "corrupt dataset " + name);
  if (H5Pget_layout(dcpl.get()) != H5D_COMPACT) return;
  const size_t element = H5Tget_size(type);
  const hsize_t stored = H5Dget_storage_size(dset);
  if (element == 0 || n > stored / element)
    fail(path, "corrupt dataset " + name + ": its compact storage holds " + std::to_string(stored) +
                   " bytes, too few for " + std::to_string(n) + " values");
}

Dataset1D open_1d(const fs::path& path, hid_t loc, const std::string& prefix, const char* name) {
  Dataset1D d;
  d.name = prefix + name;
  d.id = Hid(H5Dopen2(loc, name, H5P_DEFAULT), H5Dclose);
  if (!d.id.ok()) fail(path, "cannot open dataset " + d.name + ": " + h5_last_error());
  Hid space(H5Dget_space(d.id.get()), H5Sclose);
  if (!space.ok()) fail(path, "corrupt dataset " + d.name);
  int rank = H5Sget_simple_extent_ndims(space.get());
  hsize_t dims[8] = {0};
  if (rank < 0 || rank > 8 || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0)
    fail(path, "corrupt dataset " + d.name);
  if (rank != 1 && !(rank == 2 && (dims[1] == 1 || dims[0] == 1)))
    fail(path, "dataset " + d.name + " must be one-dimensional (rank " + std::to_string(rank) + ")");
  d.n = rank == 1 ? dims[0] : dims[0] * dims[1];
  Hid type(H5Dget_type(d.id.get()), H5Tclose);
  d.cls = type.ok() ? H5Tget_class(type.get()) : H5T_NO_CLASS;
  if (d.cls != H5T_INTEGER && d.cls != H5T_FLOAT && d.cls != H5T_ENUM)  // h5py stores bool as enum
    fail(path, "dataset " + d.name + " is not numeric");
  // A corrupt type message can claim any element size; HDF5 1.10 then reads past its buffers.
  const size_t element = H5Tget_size(type.get());
  if (element == 0 || element > 16)
    fail(path, "corrupt dataset " + d.name + ": " + std::to_string(element) + "-byte numbers");
  std::string miss = missing_filters(d.id.get());
  if (!miss.empty()) fail(path, "dataset " + d.name + ": " + miss);
  check_compact_storage(path, d.id.get(), d.name, d.n, type.get());
  return d;
}

// Reads the whole dataset in blocks, converting to T, and calls f(block, first index, count).
template <typename T, typename F>
void read_blocks(const fs::path& path, const Dataset1D& d, hid_t memtype, F&& f) {
  constexpr size_t kBlock = size_t(1) << 20;
  std::vector<T> buf(std::min(d.n, kBlock));
  Hid fspace(H5Dget_space(d.id.get()), H5Sclose);
  int rank = H5Sget_simple_extent_ndims(fspace.get());
  for (size_t first = 0; first < d.n; first += kBlock) {
    const size_t cnt = std::min(kBlock, d.n - first);
    hsize_t start[2] = {first, 0}, count[2] = {cnt, 1};
    if (rank == 2) {
      hsize_t dims[2];
      H5Sget_simple_extent_dims(fspace.get(), dims, nullptr);
      if (dims[0] == 1) {
        start[0] = 0;
        start[1] = first;
        count[0] = 1;
        count[1] = cnt;
      }
    }
    hsize_t mcount = cnt;
    Hid mspace(H5Screate_simple(1, &mcount, nullptr), H5Sclose);
    if (H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr) < 0 ||
        H5Dread(d.id.get(), memtype, mspace.get(), fspace.get(), H5P_DEFAULT, buf.data()) < 0) {
      std::string why = h5_last_error();
      std::string miss = missing_filters(d.id.get());
      fail(path, "cannot read dataset " + d.name + " (truncated or corrupt file?)" + (why.empty() ? "" : ": " + why) +
                     (miss.empty() ? "" : "; " + miss));
    }
    f(buf.data(), first, cnt);
  }
}

std::vector<int64_t> read_int64(const fs::path& path, hid_t loc, const std::string& prefix, const char* name) {
  Dataset1D d = open_1d(path, loc, prefix, name);
  std::vector<int64_t> out(d.n);
  if (d.cls == H5T_FLOAT) {
    read_blocks<double>(path, d, H5T_NATIVE_DOUBLE, [&](const double* b, size_t first, size_t cnt) {
      for (size_t i = 0; i < cnt; ++i) {
        if (!(std::fabs(b[i]) < 9e18))
          fail(path, d.name + "[" + std::to_string(first + i) + "] is not a finite integer");
        out[first + i] = std::llround(b[i]);
      }
    });
  } else {
    read_blocks<int64_t>(path, d, H5T_NATIVE_INT64, [&](const int64_t* b, size_t first, size_t cnt) {
      std::copy(b, b + cnt, out.begin() + first);
    });
  }
  return out;
}

template <typename T>
void write_1d(const fs::path& path, hid_t loc, const char* name, hid_t filetype, hid_t memtype, const std::vector<T>& v,
              int deflate) {
  hsize_t n = v.size();
  Hid space(H5Screate_simple(1, &n, nullptr), H5Sclose);
  Hid dcpl(H5Pcreate(H5P_DATASET_CREATE), H5Pclose);
  if (n > 0 && deflate > 0) {
    hsize_t chunk = std::min<hsize_t>(n, 1 << 16);
    H5Pset_chunk(dcpl.get(), 1, &chunk);
    H5Pset_shuffle(dcpl.get());
    H5Pset_deflate(dcpl.get(), unsigned(std::min(deflate, 9)));
  }
  Hid d(H5Dcreate2(loc, name, filetype, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT), H5Dclose);
  if (!d.ok()) fail(path, std::string("cannot create dataset ") + name + ": " + h5_last_error());
  if (n > 0 && H5Dwrite(d.get(), memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()) < 0)
    fail(path, std::string("cannot write dataset ") + name + ": " + h5_last_error());
}

uint32_t read_uint_attr(hid_t obj, const char* name) {
  if (H5Aexists(obj, name) <= 0) return 0;
  Hid a(H5Aopen(obj, name, H5P_DEFAULT), H5Aclose);
  if (!a.ok()) return 0;
  Hid space(H5Aget_space(a.get()), H5Sclose);  // one value only: H5Aread writes every element
  if (!space.ok() || H5Sget_simple_extent_npoints(space.get()) != 1) return 0;
  int64_t v = 0;
  if (H5Aread(a.get(), H5T_NATIVE_INT64, &v) < 0 || v <= 0 || v > 65536) return 0;
  return uint32_t(v);
}

void write_uint_attr(hid_t obj, const char* name, uint32_t v) {
  Hid space(H5Screate(H5S_SCALAR), H5Sclose);
  Hid a(H5Acreate2(obj, name, H5T_STD_U32LE, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose);
  H5Awrite(a.get(), H5T_NATIVE_UINT32, &v);
}

}  // namespace

bool h5_blosc_available() {
  QuietHdf5 quiet;
  return H5Zfilter_avail(kBloscFilter) > 0;
}

namespace {

// The event group: /events, or the root when the file has no /events.
hid_t event_location(const fs::path& path, hid_t file, Hid& group, std::string& prefix) {
  prefix = "/";
  if (!link_exists(file, "events")) return file;
  group = Hid(H5Gopen2(file, "events", H5P_DEFAULT), H5Gclose);
  if (!group.ok()) fail(path, "/events is not a group: " + h5_last_error());
  prefix = "/events/";
  return group.get();
}

void read_polarity(const fs::path& path, Dataset1D& dp, EventStream& ev) {
  read_blocks<double>(path, dp, H5T_NATIVE_DOUBLE, [&](const double* b, size_t first, size_t cnt) {
    for (size_t i = 0; i < cnt; ++i) {
      if (b[i] > 0)
        ev.p[first + i] = 1;
      else if (b[i] == 0 || b[i] == -1)
        ev.p[first + i] = -1;
      else
        fail(path, "event " + std::to_string(first + i) + " has polarity " + std::to_string(b[i]) +
                       " (expected 0/1 or -1/1)");
    }
  });
}

// Times in seconds; `off` is /t_offset in us (0 when not applied).
void read_times(const fs::path& path, Dataset1D& dt, TimeUnit unit, int64_t off, EventStream& ev) {
  const double units_per_s = unit == TimeUnit::s ? 1.0 : unit == TimeUnit::ms ? 1e3 : unit == TimeUnit::us ? 1e6 : 1e9;
  if (dt.cls == H5T_FLOAT) {
    read_blocks<double>(path, dt, H5T_NATIVE_DOUBLE, [&](const double* b, size_t first, size_t cnt) {
      for (size_t i = 0; i < cnt; ++i) ev.t[first + i] = b[i] / units_per_s + double(off) / 1e6;
    });
    return;
  }
  // Integer times: add the offset in integers where the unit allows it (and the sum fits), then
  // divide once.
  const int64_t scale = unit == TimeUnit::us ? 1 : unit == TimeUnit::ns ? 1000 : 0;
  read_blocks<int64_t>(path, dt, H5T_NATIVE_INT64, [&](const int64_t* b, size_t first, size_t cnt) {
    for (size_t i = 0; i < cnt; ++i) {
      int64_t scaled_off = 0, sum = 0;
      if (scale && !__builtin_mul_overflow(off, scale, &scaled_off) && !__builtin_add_overflow(b[i], scaled_off, &sum))
        ev.t[first + i] = double(sum) / (scale == 1 ? 1e6 : 1e9);
      else
        ev.t[first + i] = double(b[i]) / units_per_s + double(off) / 1e6;
    }
  });
}

void read_exposure(const fs::path& path, hid_t file, int64_t off, H5Events& out) {
  if (!link_exists(file, "exposure")) return;
  Hid g(H5Gopen2(file, "exposure", H5P_DEFAULT), H5Gclose);
  if (!g.ok()) fail(path, "/exposure is not a group");
  if (!link_exists(g.get(), "start_us") || !link_exists(g.get(), "end_us"))
    fail(path, "/exposure needs both start_us and end_us");
  auto s = read_int64(path, g.get(), "/exposure/", "start_us");
  auto e = read_int64(path, g.get(), "/exposure/", "end_us");
  if (s.size() != e.size())
    fail(path, "/exposure/start_us has " + std::to_string(s.size()) + " entries, /exposure/end_us " +
                   std::to_string(e.size()));
  for (size_t i = 0; i < s.size(); ++i) {
    if (e[i] < s[i]) fail(path, "exposure window " + std::to_string(i) + " ends before it starts");
    out.exposure_start.push_back((double(s[i]) + double(off)) / 1e6);
    out.exposure_end.push_back((double(e[i]) + double(off)) / 1e6);
  }
}

int64_t read_t_offset(const fs::path& path, hid_t file) {
  if (!link_exists(file, "t_offset")) return 0;
  Hid d(H5Dopen2(file, "t_offset", H5P_DEFAULT), H5Dclose);
  if (!d.ok()) fail(path, "cannot read /t_offset: " + h5_last_error());
  Hid space(H5Dget_space(d.get()), H5Sclose), type(H5Dget_type(d.get()), H5Tclose);
  if (!space.ok() || !type.ok() || H5Sget_simple_extent_npoints(space.get()) != 1 || H5Tget_size(type.get()) > 16)
    fail(path, "/t_offset must be a single number");
  check_compact_storage(path, d.get(), "/t_offset", 1, type.get());
  int64_t v = 0;
  if (H5Dread(d.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v) < 0)
    fail(path, "cannot read /t_offset: " + h5_last_error());
  return v;
}

void read_coords(const fs::path& path, Dataset1D& d, std::vector<uint16_t>& dst, uint32_t& mx) {
  read_blocks<double>(path, d, H5T_NATIVE_DOUBLE, [&](const double* b, size_t first, size_t cnt) {
    for (size_t i = 0; i < cnt; ++i) {
      const double v = b[i];
      if (!(v >= 0 && v <= 65535) || v != std::floor(v))
        fail(path, "event " + std::to_string(first + i) + ": " + d.name + " = " + std::to_string(v) +
                       " is not a pixel coordinate");
      dst[first + i] = uint16_t(v);
      mx = std::max(mx, uint32_t(v));
    }
  });
}

// Everything read_events_h5 reads, from an open file; `path` names it in errors.
H5Events read_open_file(const fs::path& path, hid_t file, const H5ReadOptions& opt) {
  Hid group;
  std::string prefix;
  const hid_t loc = event_location(path, file, group, prefix);
  for (const char* n : {"x", "y", "t", "p"})
    if (!link_exists(loc, n))
      fail(path, "no dataset " + prefix + n + " (expected /events/{x,y,t,p} or root-level x, y, t, p)");
  Dataset1D dx = open_1d(path, loc, prefix, "x"), dy = open_1d(path, loc, prefix, "y"),
            dt = open_1d(path, loc, prefix, "t"), dp = open_1d(path, loc, prefix, "p");
  if (dx.n != dt.n || dy.n != dt.n || dp.n != dt.n)
    fail(path, "event datasets differ in length (x " + std::to_string(dx.n) + ", y " + std::to_string(dy.n) + ", t " +
                   std::to_string(dt.n) + ", p " + std::to_string(dp.n) + ")");
  const size_t n = dt.n;
  H5Events out;
  out.t_offset_us = read_t_offset(path, file);
  const int64_t off = opt.apply_t_offset ? out.t_offset_us : 0;
  EventStream& ev = out.events;
  ev.x.resize(n);
  ev.y.resize(n);
  ev.t.resize(n);
  ev.p.resize(n);
  uint32_t max_x = 0, max_y = 0;
  read_coords(path, dx, ev.x, max_x);
  read_coords(path, dy, ev.y, max_y);
  read_polarity(path, dp, ev);
  read_times(path, dt, opt.unit, off, ev);
  uint32_t aw = read_uint_attr(loc, "width"), ah = read_uint_attr(loc, "height");
  ev.width = opt.width ? opt.width : aw ? aw : (n ? max_x + 1 : 0);
  ev.height = opt.height ? opt.height : ah ? ah : (n ? max_y + 1 : 0);
  ev.validate(path.string());
  read_exposure(path, file, off, out);
  return out;
}

}  // namespace

H5Events read_events_h5(const fs::path& path, const H5ReadOptions& opt) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) fail(path, "event file is missing");
  QuietHdf5 quiet;
  if (H5Fis_hdf5(path.string().c_str()) <= 0) fail(path, "not an HDF5 file (or a truncated one)");
  Hid file(H5Fopen(path.string().c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!file.ok()) fail(path, "cannot open HDF5 file (truncated or corrupt?): " + h5_last_error());
  return read_open_file(path, file.get(), opt);
}

H5Events read_events_h5_image(const void* data, size_t size, const std::string& name, const H5ReadOptions& opt) {
  QuietHdf5 quiet;
  Hid fapl(H5Pcreate(H5P_FILE_ACCESS), H5Pclose);
  if (!fapl.ok() || H5Pset_fapl_core(fapl.get(), 1 << 16, 0) < 0 ||
      (size && H5Pset_file_image(fapl.get(), const_cast<void*>(data), size) < 0))
    fail(name, "cannot set up an in-memory HDF5 file: " + h5_last_error());
  Hid file(H5Fopen(name.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose);
  if (!file.ok()) fail(name, "cannot open HDF5 file (truncated or corrupt?): " + h5_last_error());
  return read_open_file(name, file.get(), opt);
}

void write_events_h5(const fs::path& path, const EventStream& ev, const std::vector<double>& exposure_start,
                     const std::vector<double>& exposure_end, const H5WriteOptions& opt) {
  ev.validate(path.string() + " (events to write)");
  if (exposure_start.size() != exposure_end.size())
    throw std::invalid_argument(path.string() + ": " + std::to_string(exposure_start.size()) + " exposure starts but " +
                                std::to_string(exposure_end.size()) + " ends");
  const size_t n = ev.size();
  std::vector<int64_t> t(n);
  std::vector<uint8_t> p(n);
  for (size_t i = 0; i < n; ++i) {
    t[i] = std::llround(ev.t[i] * 1e6) - opt.t_offset_us;
    p[i] = ev.p[i] > 0 ? 1 : 0;
  }
  std::vector<uint64_t> ms_to_idx;
  if (n) {
    // ms_to_idx[k] = index of the first event with t >= k ms (t relative to t_offset)
    const int64_t last_ms = std::max<int64_t>(0, t.back() / 1000);
    if (t.front() >= 0 && last_ms < (int64_t(1) << 32)) {
      size_t j = 0;
      for (int64_t k = 0; k <= last_ms; ++k) {
        while (j < n && t[j] < k * 1000) ++j;
        ms_to_idx.push_back(j);
      }
    }
  }
  std::vector<int64_t> es(exposure_start.size()), ee(exposure_end.size());
  for (size_t i = 0; i < es.size(); ++i) {
    es[i] = std::llround(exposure_start[i] * 1e6) - opt.t_offset_us;
    ee[i] = std::llround(exposure_end[i] * 1e6) - opt.t_offset_us;
  }
  write_file_atomic(path, [&](const fs::path& tmp) {
    QuietHdf5 quiet;
    Hid file(H5Fcreate(tmp.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT), H5Fclose);
    if (!file.ok()) fail(path, "cannot create HDF5 file: " + h5_last_error());
    Hid g(H5Gcreate2(file.get(), "events", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
    if (!g.ok()) fail(path, "cannot create /events: " + h5_last_error());
    write_1d(path, g.get(), "x", H5T_STD_U16LE, H5T_NATIVE_UINT16, ev.x, opt.deflate_level);
    write_1d(path, g.get(), "y", H5T_STD_U16LE, H5T_NATIVE_UINT16, ev.y, opt.deflate_level);
    write_1d(path, g.get(), "t", H5T_STD_I64LE, H5T_NATIVE_INT64, t, opt.deflate_level);
    write_1d(path, g.get(), "p", H5T_STD_U8LE, H5T_NATIVE_UINT8, p, opt.deflate_level);
    write_uint_attr(g.get(), "width", ev.width);
    write_uint_attr(g.get(), "height", ev.height);
    {
      Hid space(H5Screate(H5S_SCALAR), H5Sclose);
      Hid d(H5Dcreate2(file.get(), "t_offset", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
            H5Dclose);
      if (!d.ok() || H5Dwrite(d.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &opt.t_offset_us) < 0)
        fail(path, "cannot write /t_offset: " + h5_last_error());
    }
    write_1d(path, file.get(), "ms_to_idx", H5T_STD_U64LE, H5T_NATIVE_UINT64, ms_to_idx, opt.deflate_level);
    if (!es.empty()) {
      Hid eg(H5Gcreate2(file.get(), "exposure", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose);
      write_1d(path, eg.get(), "start_us", H5T_STD_I64LE, H5T_NATIVE_INT64, es, 0);
      write_1d(path, eg.get(), "end_us", H5T_STD_I64LE, H5T_NATIVE_INT64, ee, 0);
    }
    if (H5Fflush(file.get(), H5F_SCOPE_GLOBAL) < 0) fail(path, "cannot flush HDF5 file: " + h5_last_error());
  });
}

}  // namespace evflow::io
