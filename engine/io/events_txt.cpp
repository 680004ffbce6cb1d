#include "io/events_txt.h"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "io/atomic_file.h"

namespace evflow::io {

namespace fs = std::filesystem;

double seconds_per(TimeUnit u) {
  switch (u) {
    case TimeUnit::s:
      return 1.0;
    case TimeUnit::ms:
      return 1e-3;
    case TimeUnit::us:
      return 1e-6;
    case TimeUnit::ns:
      return 1e-9;
  }
  return 1.0;
}

static int decimal_shift(TimeUnit u) {  // seconds = value * 10^-shift
  switch (u) {
    case TimeUnit::s:
      return 0;
    case TimeUnit::ms:
      return 3;
    case TimeUnit::us:
      return 6;
    case TimeUnit::ns:
      return 9;
  }
  return 0;
}

TimeUnit parse_time_unit(const std::string& s) {
  if (s == "s") return TimeUnit::s;
  if (s == "ms") return TimeUnit::ms;
  if (s == "us") return TimeUnit::us;
  if (s == "ns") return TimeUnit::ns;
  throw std::invalid_argument("unknown time unit '" + s + "' (s, ms, us or ns)");
}

std::string to_string(TimeUnit u) {
  switch (u) {
    case TimeUnit::s:
      return "s";
    case TimeUnit::ms:
      return "ms";
    case TimeUnit::us:
      return "us";
    case TimeUnit::ns:
      return "ns";
  }
  return "?";
}

namespace {

// Parses a decimal number token and returns it times 10^-shift as the nearest double.
bool parse_scaled(std::string_view tok, int shift, double& out) {
  std::string digits;
  bool neg = false, any = false, dot = false;
  long frac = 0;
  size_t i = 0;
  if (i < tok.size() && (tok[i] == '+' || tok[i] == '-')) neg = tok[i++] == '-';
  for (; i < tok.size(); ++i) {
    char c = tok[i];
    if (c >= '0' && c <= '9') {
      any = true;
      if (digits.empty() && c == '0') {
        if (dot) ++frac;
        continue;
      }  // drop leading zeros
      digits += c;
      if (dot) ++frac;
    } else if (c == '.' && !dot) {
      dot = true;
    } else {
      break;
    }
  }
  if (!any) return false;
  long exp10 = 0;
  if (i < tok.size()) {
    if (tok[i] != 'e' && tok[i] != 'E') return false;
    ++i;
    long e = 0;
    auto [p, ec] = std::from_chars(tok.data() + i, tok.data() + tok.size(), e);
    if (ec != std::errc() || p != tok.data() + tok.size()) {
      if (i < tok.size() && tok[i] == '+') {
        auto [p2, ec2] = std::from_chars(tok.data() + i + 1, tok.data() + tok.size(), e);
        if (ec2 != std::errc() || p2 != tok.data() + tok.size()) return false;
      } else {
        return false;
      }
    }
    if (e > 100000 || e < -100000) return false;
    exp10 = e;
  }
  if (digits.empty()) {
    out = neg ? -0.0 : 0.0;
    return true;
  }
  std::string s = (neg ? "-" : "") + digits + "e" + std::to_string(exp10 - frac - shift);
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(out);
}

// Shortest round-trip decimal of v, times 10^shift, in fixed notation.
std::string format_scaled(double v, int shift) {
  char buf[64];
  auto [p, ec] = std::to_chars(buf, buf + sizeof buf, v, std::chars_format::scientific);
  std::string_view s(buf, size_t(p - buf));
  bool neg = false;
  if (!s.empty() && s[0] == '-') {
    neg = true;
    s.remove_prefix(1);
  }
  size_t e = s.find('e');
  std::string mant(s.substr(0, e));
  long exp10 = std::stol(std::string(s.substr(e + 1)));
  std::string digits;
  for (char c : mant)
    if (c != '.') digits += c;
  // value = digits * 10^(exp10 - (len-1)) * 10^shift
  long E = exp10 - long(digits.size() - 1) + shift;
  while (digits.size() > 1 && digits.back() == '0') {
    digits.pop_back();
    ++E;
  }
  std::string r;
  if (digits == "0") return "0";
  if (E >= 0) {
    r = digits + std::string(size_t(E), '0');
  } else {
    long pos = long(digits.size()) + E;
    if (pos > 0)
      r = digits.substr(0, size_t(pos)) + "." + digits.substr(size_t(pos));
    else
      r = "0." + std::string(size_t(-pos), '0') + digits;
  }
  return neg ? "-" + r : r;
}

std::vector<std::string_view> split_ws(std::string_view line) {
  std::vector<std::string_view> toks;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == ',' || line[i] == '\r')) ++i;
    size_t j = i;
    while (j < line.size() && !(line[j] == ' ' || line[j] == '\t' || line[j] == ',' || line[j] == '\r')) ++j;
    if (j > i) toks.push_back(line.substr(i, j - i));
    i = j;
  }
  return toks;
}

bool parse_uint(std::string_view tok, long long& v) {
  double d;
  if (!parse_scaled(tok, 0, d)) return false;
  if (d != std::floor(d) || d < 0 || d > 1e12) return false;
  v = static_cast<long long>(d);
  return true;
}

}  // namespace

EventStream read_events_txt(const fs::path& path, const TxtReadOptions& opt) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error(path.string() + ": cannot open event file (missing or unreadable)");
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EventStream ev;
  uint32_t hdr_w = 0, hdr_h = 0;
  bool first_data = true;
  uint32_t max_x = 0, max_y = 0;
  const int shift = decimal_shift(opt.unit);
  size_t pos = 0, line_no = 0;
  auto err = [&](const std::string& what) {
    return std::runtime_error(path.string() + ":" + std::to_string(line_no) + ": " + what);
  };
  while (pos < text.size()) {
    size_t nl = text.find('\n', pos);
    if (nl == std::string::npos) nl = text.size();
    std::string_view line(text.data() + pos, nl - pos);
    pos = nl + 1;
    ++line_no;
    auto toks = split_ws(line);
    if (toks.empty() || toks[0][0] == '#') continue;
    if (first_data) {
      first_data = false;
      long long w, h;
      if (toks.size() == 2 && parse_uint(toks[0], w) && parse_uint(toks[1], h)) {
        if (w <= 0 || h <= 0 || w > 65536 || h > 65536) throw err("bad sensor size header '" + std::string(line) + "'");
        hdr_w = uint32_t(w);
        hdr_h = uint32_t(h);
        continue;
      }
    }
    if (toks.size() != 4)
      throw err("expected 't x y p', found " + std::to_string(toks.size()) + " fields: '" +
                std::string(line.substr(0, 80)) + "'");
    double t, pd;
    long long x, y;
    if (!parse_scaled(toks[0], shift, t)) throw err("bad timestamp '" + std::string(toks[0]) + "'");
    if (!parse_uint(toks[1], x) || x > 65535) throw err("bad x coordinate '" + std::string(toks[1]) + "'");
    if (!parse_uint(toks[2], y) || y > 65535) throw err("bad y coordinate '" + std::string(toks[2]) + "'");
    if (!parse_scaled(toks[3], 0, pd)) throw err("bad polarity '" + std::string(toks[3]) + "'");
    int8_t p;
    switch (opt.polarity) {
      case PolarityCoding::zero_one:
        if (pd == 1)
          p = 1;
        else if (pd == 0)
          p = -1;
        else
          throw err("polarity " + std::string(toks[3]) + " is not 0 or 1");
        break;
      case PolarityCoding::minus_one_one:
        if (pd == 1)
          p = 1;
        else if (pd == -1)
          p = -1;
        else
          throw err("polarity " + std::string(toks[3]) + " is not -1 or 1");
        break;
      default:
        p = pd == 1 ? 1 : -1;
    }
    max_x = std::max(max_x, uint32_t(x));
    max_y = std::max(max_y, uint32_t(y));
    ev.push(uint16_t(x), uint16_t(y), t, p);
  }
  ev.width = opt.width ? opt.width : hdr_w ? hdr_w : (ev.size() ? max_x + 1 : 0);
  ev.height = opt.height ? opt.height : hdr_h ? hdr_h : (ev.size() ? max_y + 1 : 0);
  ev.validate(path.string());
  return ev;
}

void write_events_txt(const fs::path& path, const EventStream& ev, const TxtWriteOptions& opt) {
  ev.validate(path.string() + " (events to write)");
  const int shift = decimal_shift(opt.unit);
  write_file_atomic(path, [&](const fs::path& tmp) {
    std::ofstream f(tmp, std::ios::binary);
    if (!f) throw std::runtime_error(path.string() + ": cannot create file");
    std::string buf;
    buf.reserve(1 << 20);
    if (opt.header) buf += std::to_string(ev.width) + " " + std::to_string(ev.height) + "\n";
    for (size_t i = 0; i < ev.size(); ++i) {
      buf += format_scaled(ev.t[i], shift);
      buf += ' ';
      buf += std::to_string(ev.x[i]);
      buf += ' ';
      buf += std::to_string(ev.y[i]);
      buf += ' ';
      buf += ev.p[i] > 0 ? "1" : (opt.polarity == PolarityCoding::minus_one_one ? "-1" : "0");
      buf += '\n';
      if (buf.size() > (1 << 20) - 128) {
        f.write(buf.data(), std::streamsize(buf.size()));
        buf.clear();
      }
    }
    f.write(buf.data(), std::streamsize(buf.size()));
    close_or_throw(f, path);
  });
}

}  // namespace evflow::io
