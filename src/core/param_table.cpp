#include "agvslam/core/param_table.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <utility>

#include "agvslam/core/error.h"

namespace agvslam::params {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

std::string number(double v) { return detail::format_number(v); }
}  // namespace

// ---- Range ---------------------------------------------------------------------------------------------------

Range Range::any() { return Range{}; }

Range Range::finite() { return open(-kInf, kInf); }

Range Range::interval(double lo, double hi, bool lo_open, bool hi_open) {
  Range r;
  r.intervals_.push_back({lo, hi, lo_open, hi_open});
  return r;
}

Range Range::closed(double lo, double hi) { return interval(lo, hi, false, false); }
Range Range::open(double lo, double hi) { return interval(lo, hi, true, true); }
Range Range::left_open(double lo, double hi) { return interval(lo, hi, true, false); }
Range Range::right_open(double lo, double hi) { return interval(lo, hi, false, true); }
Range Range::at_least(double lo) { return right_open(lo, kInf); }
Range Range::above(double lo) { return open(lo, kInf); }
Range Range::at_most(double hi) { return left_open(-kInf, hi); }
Range Range::value(double v) { return closed(v, v); }

Range Range::operator|(const Range& other) const {
  if (intervals_.empty() || other.intervals_.empty()) return any();
  Range r = *this;
  r.intervals_.insert(r.intervals_.end(), other.intervals_.begin(), other.intervals_.end());
  return r;
}

Range Range::multiple_of(int step) const {
  Range r = *this;
  r.step_ = step;
  return r;
}

Range Range::odd() const {
  Range r = *this;
  r.odd_ = true;
  return r;
}

bool Range::contains(double v) const {
  if (intervals_.empty()) return true;
  if (step_ > 0 && std::fmod(v, step_) != 0) return false;
  if (odd_ && std::fabs(std::fmod(v, 2.0)) != 1) return false;
  for (const Interval& i : intervals_) {
    const bool above_lo = i.lo_open ? v > i.lo : v >= i.lo;
    const bool below_hi = i.hi_open ? v < i.hi : v <= i.hi;
    if (above_lo && below_hi) return true;
  }
  return false;
}

std::string Range::text() const {
  std::string out;
  for (const Interval& i : intervals_) {
    if (std::isinf(i.lo) && std::isinf(i.hi)) continue;  // finite(): the type word says it
    std::string one;
    if (i.lo == i.hi) {
      one = number(i.lo);
    } else if (std::isinf(i.hi)) {
      one = (i.lo_open ? "> " : ">= ") + number(i.lo);
    } else if (std::isinf(i.lo)) {
      one = (i.hi_open ? "< " : "<= ") + number(i.hi);
    } else {
      one = std::string("in ") + (i.lo_open ? "(" : "[") + number(i.lo) + ", " + number(i.hi) + (i.hi_open ? ")" : "]");
    }
    out += (out.empty() ? "" : " or ") + one;
  }
  return out;
}

// ---- Text ----------------------------------------------------------------------------------------------------

Text Text::any() { return Text{}; }

Text Text::non_empty() { return length(1, std::string::npos); }

Text Text::length(std::size_t min_chars, std::size_t max_chars) {
  Text t;
  t.min_ = min_chars;
  t.max_ = max_chars;
  return t;
}

Text Text::one_of(std::vector<std::string> values) {
  Text t;
  t.values_ = std::move(values);
  return t;
}

bool Text::accepts(const std::string& value) const {
  if (value.size() < min_ || value.size() > max_) return false;
  if (values_.empty()) return true;
  for (const std::string& v : values_) {
    if (v == value) return true;
  }
  return false;
}

std::string Text::text() const {
  if (!values_.empty()) {
    std::string out = "one of ";
    for (std::size_t i = 0; i < values_.size(); ++i) out += (i == 0 ? "" : ", ") + values_[i];
    return out;
  }
  if (max_ != std::string::npos) {
    return "a string of " + std::to_string(min_) + " to " + std::to_string(max_) + " characters";
  }
  return min_ > 0 ? "a non-empty string" : "a string";
}

// ---- detail --------------------------------------------------------------------------------------------------

namespace detail {

std::string with_reason(std::string text, const char* reason) {
  if (reason != nullptr && *reason != '\0') text += std::string(" (") + reason + ")";
  return text;
}

std::string number_expectation(const char* type, const Range& range, const char* unit, const char* reason) {
  std::string text = type;
  if (range.is_odd()) text = "an odd integer";
  if (range.step() > 0) text = "a multiple of " + std::to_string(range.step());
  const std::string values = range.text();
  const bool has_unit = unit != nullptr && *unit != '\0';
  if (!values.empty()) {
    text += " " + values;
    if (has_unit) text += std::string(" ") + unit;
  } else if (has_unit) {
    text += std::string(" (") + unit + ")";
  }
  return with_reason(text, reason);
}

std::string text_expectation(const Text& rule, const char* reason) { return with_reason(rule.text(), reason); }

std::string enum_expectation(const std::string& names, const char* reason) {
  return with_reason("one of " + names, reason);
}

std::string id_expectation(uint32_t max_id, const char* reason) {
  return with_reason("an id such as 0x300, at most " + format_id(max_id), reason);
}

std::string format_number(double value) {
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0 ? "inf" : "-inf";
  char buf[32];
  if (value == std::floor(value) && std::fabs(value) < 1e15) {
    std::snprintf(buf, sizeof buf, "%.0f", value);
    return buf;
  }
  // The shortest text that reads back as the same double: 0.1 rather than 0.10000000000000001.
  for (int precision = 1; precision <= 17; ++precision) {
    std::snprintf(buf, sizeof buf, "%.*g", precision, value);
    if (std::strtod(buf, nullptr) == value) break;
  }
  return buf;
}

std::string format_text(const std::string& value) { return value.empty() ? std::string("\"\"") : value; }

std::string format_id(uint32_t id) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "0x%X", id);
  return buf;
}

void read_id(const File& file, const std::string& section, const std::string& key, uint32_t max_id, uint32_t& value,
             const std::string& expectation) {
  std::string text;
  if (!file.read(section, key, text, expectation) || text.empty()) return;
  try {
    std::size_t used = 0;
    const unsigned long v = std::stoul(text, &used, 0);
    if (used != text.size() || v > max_id) throw std::invalid_argument(text);
    value = static_cast<uint32_t>(v);
  } catch (const std::exception&) {
    fail(file.path(), field(section, key), expectation, "'" + text + "'");
  }
}

void read_uint32(const File& file, const std::string& section, const std::string& key, uint32_t& value,
                 const std::string& expectation) {
  uint64_t wide = value;
  if (!file.read(section, key, wide, expectation)) return;
  if (wide > std::numeric_limits<uint32_t>::max()) {
    fail(file.path(), field(section, key), expectation, "'" + std::to_string(wide) + "'");
  }
  value = static_cast<uint32_t>(wide);
}

std::string field(const std::string& section, const std::string& key) { return section + "." + key; }

void fail(const std::string& source, const std::string& where, const std::string& expectation, const std::string& got) {
  throw InputError(source, where, "expected " + expectation + (got.empty() ? std::string() : ", got " + got));
}

std::string item(const std::string& key, const std::string& value, const char* unit) {
  std::string out = key + "=" + value;
  if (unit == nullptr || *unit == '\0') return out;
  // A key that ends with its unit (roi_margin_px, rate_hz) says it already.
  const std::string suffix = "_" + std::string(unit);
  bool named = key.size() > suffix.size();
  for (std::size_t i = 0; named && i < suffix.size(); ++i) {
    named = std::tolower(static_cast<unsigned char>(key[key.size() - suffix.size() + i])) ==
            std::tolower(static_cast<unsigned char>(suffix[i]));
  }
  return named ? out : out + " " + unit;
}

}  // namespace detail

void read_sections(const File& file, const std::vector<SectionReader>& sections) {
  std::vector<std::string> names;
  for (const SectionReader& s : sections) names.push_back(s.section);
  file.check_sections(names);
  for (const SectionReader& s : sections) s.read(file);
}

}  // namespace agvslam::params
