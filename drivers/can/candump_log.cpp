#include "agvslam/drivers/can/candump_log.h"

#include <cctype>
#include <cstdio>
#include <limits>

#include "agvslam/core/error.h"

namespace agvslam::drivers::can {
namespace {

constexpr uint32_t kCanErrFlag = 0x20000000U;
constexpr uint32_t kCanEffMask = 0x1FFFFFFFU;

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

}  // namespace

std::optional<CandumpRecord> parse_candump_line(const std::string& line, const std::string& source, int line_no) {
  const std::string where = "line " + std::to_string(line_no);
  std::size_t p = line.find_first_not_of(" \t\r");
  if (p == std::string::npos || line[p] == '#') return std::nullopt;
  auto fail = [&](const std::string& what) -> std::optional<CandumpRecord> {
    throw InputError(source, where, "expected a candump -L line '(<sec>.<usec>) <iface> <id>#<hex>': " + what);
  };
  if (line[p] != '(') return fail("no '(' time stamp");
  const std::size_t close = line.find(')', p);
  if (close == std::string::npos) return fail("no ')'");
  CandumpRecord r;
  {
    const std::string ts = line.substr(p + 1, close - p - 1);
    const std::size_t dot = ts.find('.');
    if (dot == std::string::npos || dot == 0) return fail("time stamp without '.'");
    int64_t sec = 0;
    for (std::size_t i = 0; i < dot; ++i) {
      if (std::isdigit(static_cast<unsigned char>(ts[i])) == 0) return fail("bad time stamp");
      // At most kMaxSec seconds, so that sec * 1e9 + the fraction fits in int64 nanoseconds (until 2262).
      constexpr int64_t kMaxSec = std::numeric_limits<int64_t>::max() / 1000000000 - 1;
      const int digit = ts[i] - '0';
      if (sec > (kMaxSec - digit) / 10) return fail("time stamp beyond " + std::to_string(kMaxSec) + " s");
      sec = sec * 10 + digit;
    }
    int64_t frac = 0;
    int digits = 0;
    for (std::size_t i = dot + 1; i < ts.size(); ++i) {
      if (std::isdigit(static_cast<unsigned char>(ts[i])) == 0) return fail("bad time stamp");
      if (digits < 9) {
        frac = frac * 10 + (ts[i] - '0');
        ++digits;
      }
    }
    for (; digits < 9; ++digits) frac *= 10;
    r.t_ns = sec * 1000000000 + frac;
  }
  p = line.find_first_not_of(' ', close + 1);
  if (p == std::string::npos) return fail("no interface");
  std::size_t sp = line.find(' ', p);
  if (sp == std::string::npos) return fail("no frame after the interface");
  r.interface = line.substr(p, sp - p);
  p = line.find_first_not_of(' ', sp);
  if (p == std::string::npos) return fail("no frame after the interface");
  std::size_t end = line.find_first_of(" \t\r", p);
  const std::string frame = line.substr(p, end == std::string::npos ? std::string::npos : end - p);
  const std::size_t hash = frame.find('#');
  if (hash == std::string::npos || (hash != 3 && hash != 8)) return fail("id must be 3 or 8 hex digits before '#'");
  uint32_t id = 0;
  for (std::size_t i = 0; i < hash; ++i) {
    const int v = hex_value(frame[i]);
    if (v < 0) return fail("bad hex digit in the id");
    id = (id << 4) | static_cast<uint32_t>(v);
  }
  r.frame.extended = hash == 8;
  r.error_frame = (id & kCanErrFlag) != 0;
  r.frame.id = r.frame.extended ? (id & kCanEffMask) : id;
  std::size_t q = hash + 1;
  if (q < frame.size() && frame[q] == '#') {
    r.frame.fd = true;
    if (q + 1 >= frame.size() || hex_value(frame[q + 1]) < 0) return fail("CAN FD flags nibble missing after '##'");
    r.fd_flags = static_cast<uint8_t>(hex_value(frame[q + 1]));
    q += 2;
  } else if (q < frame.size() && (frame[q] == 'R' || frame[q] == 'r')) {
    r.remote = true;
    return r;
  }
  const std::size_t max_len = r.frame.fd ? 64 : 8;
  std::size_t n = 0;
  while (q < frame.size()) {
    if (frame[q] == '.') {  // candump may separate bytes with '.'
      ++q;
      continue;
    }
    if (q + 1 >= frame.size()) return fail("odd number of hex digits in the data");
    const int hi = hex_value(frame[q]);
    const int lo = hex_value(frame[q + 1]);
    if (hi < 0 || lo < 0) return fail("bad hex digit in the data");
    if (n >= max_len) return fail("more than " + std::to_string(max_len) + " data bytes");
    r.frame.data[n++] = static_cast<uint8_t>((hi << 4) | lo);
    q += 2;
  }
  r.frame.len = static_cast<uint8_t>(n);
  return r;
}

std::string format_candump_line(const CanFrameBytes& f, const std::string& interface, int64_t t_ns) {
  char head[96];
  std::snprintf(head, sizeof head, "(%lld.%06lld) %s ", static_cast<long long>(t_ns / 1000000000),
                static_cast<long long>((t_ns % 1000000000) / 1000), interface.c_str());
  std::string s = head;
  char id[16];
  std::snprintf(id, sizeof id, f.extended ? "%08X" : "%03X", f.id);
  s += id;
  s += f.fd ? "##0" : "#";
  static const char* hex = "0123456789ABCDEF";
  for (std::size_t i = 0; i < f.len; ++i) {
    s += hex[f.data[i] >> 4];
    s += hex[f.data[i] & 0xF];
  }
  return s;
}

}  // namespace agvslam::drivers::can
