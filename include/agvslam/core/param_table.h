#pragma once
// One table per configuration struct: the single list of its settings that drives reading a params section,
// rejecting unknown keys, validating, and the start-up echo (the model is Basalt's one serialize() per config).
//
//   const params::Table<SgbmConfig>& sgbm_params() {
//     static const params::Table<SgbmConfig> table =
//         params::Table<SgbmConfig>("sgbm", {
//             {"min_disparity", &SgbmConfig::min_disparity, Range::closed(0, 1024), "px"},
//             {"mode", &SgbmConfig::mode, sgbm_mode_names()},
//             ...})
//             .check("p2", [](const SgbmConfig& g) { return g.p2 > g.p1; }, "p2 > p1");
//     return table;
//   }
//
// A new setting is one line here (key, member, allowed values, unit, and why the range is what it is when that
// is not obvious) plus its line in the YAML file; the default stays in the struct's member initialiser. Rules
// between settings are .check() lines; values derived from several settings can be echoed with .summary().
//
// Errors are InputError(source, "section.key", "expected <type> <range> <unit> (<reason>), got <value>").
// The echo is one line per table: "section: key=value unit, key=value unit, ..." (the unit is left out where the
// key already ends with it, e.g. roi_margin_px=4).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "agvslam/core/params_file.h"

namespace agvslam::params {

// The numbers a setting accepts: one interval or the union of several, optionally only odd numbers or multiples
// of a step. Bounds are doubles, which hold every int exactly. NaN and +-inf are in no range but any().
class Range {
 public:
  static Range any();
  static Range finite();                          // any number but NaN and +-inf
  static Range closed(double lo, double hi);      // [lo, hi]
  static Range open(double lo, double hi);        // (lo, hi)
  static Range left_open(double lo, double hi);   // (lo, hi]
  static Range right_open(double lo, double hi);  // [lo, hi)
  static Range at_least(double lo);               // [lo, inf)
  static Range above(double lo);                  // (lo, inf)
  static Range at_most(double hi);                // (-inf, hi]
  static Range value(double v);                   // {v}, e.g. Range::at_least(10) | Range::value(0)

  Range operator|(const Range& other) const;
  Range multiple_of(int step) const;
  Range odd() const;

  bool contains(double v) const;
  // "in [0, 1024]", ">= 0", ">= 10 or 0", "" for any(); the caller adds the type word.
  std::string text() const;
  bool is_odd() const { return odd_; }
  int step() const { return step_; }

 private:
  struct Interval {
    double lo, hi;
    bool lo_open, hi_open;
  };
  static Range interval(double lo, double hi, bool lo_open, bool hi_open);
  std::vector<Interval> intervals_;  // empty: any value
  int step_ = 0;                     // > 0: multiples of it only
  bool odd_ = false;
};

// The strings a setting accepts.
class Text {
 public:
  static Text any();
  static Text non_empty();
  static Text length(std::size_t min_chars, std::size_t max_chars);
  static Text one_of(std::vector<std::string> values);

  bool accepts(const std::string& value) const;
  // "a string", "a non-empty string", "a string of 1 to 15 characters", "one of a, b, c".
  std::string text() const;

 private:
  std::size_t min_ = 0, max_ = std::string::npos;
  std::vector<std::string> values_;  // empty: any
};

// An identifier such as a CAN id: written as a C integer literal (0x300, 768 or 01400), at most `max`, echoed in
// hex.
struct Id {
  uint32_t max;
};

// The names of an enum's values. The first name given for a value is how it is written (echo, messages); later
// names for the same value are accepted aliases.
template <class E>
class EnumNames {
 public:
  struct Name {
    const char* text;
    E value;
  };
  EnumNames(std::initializer_list<Name> names) : names_(names) {}

  const char* name(E value) const {
    for (const Name& n : names_) {
      if (n.value == value) return n.text;
    }
    return "?";
  }
  bool parse(const std::string& text, E& value) const {
    for (const Name& n : names_) {
      if (text == n.text) {
        value = n.value;
        return true;
      }
    }
    return false;
  }
  // The written names: "sgbm, hh, sgbm_3way, hh4".
  std::string list() const {
    std::string out;
    for (std::size_t i = 0; i < names_.size(); ++i) {
      bool alias = false;
      for (std::size_t j = 0; j < i; ++j) alias = alias || names_[j].value == names_[i].value;
      if (!alias) out += (out.empty() ? "" : ", ") + std::string(names_[i].text);
    }
    return out;
  }

 private:
  std::vector<Name> names_;
};

// Implementation helpers of Param and Table (param_table.cpp).
namespace detail {
std::string with_reason(std::string text, const char* reason);  // text + " (reason)" when there is one
std::string number_expectation(const char* type, const Range& range, const char* unit, const char* reason);
std::string text_expectation(const Text& rule, const char* reason);
std::string enum_expectation(const std::string& names, const char* reason);
std::string id_expectation(uint32_t max_id, const char* reason);
std::string format_number(double value);
std::string format_text(const std::string& value);  // "" for an empty string
std::string format_id(uint32_t id);                 // 0x300
// Reads a CAN-style id written as a C integer literal (0x300, 768, 01400); "" keeps `value`.
void read_id(const File& file, const std::string& section, const std::string& key, uint32_t max_id, uint32_t& value,
             const std::string& expectation);
// Reads an unsigned integer of at most 32 bits; absent keeps `value`.
void read_uint32(const File& file, const std::string& section, const std::string& key, uint32_t& value,
                 const std::string& expectation);
std::string field(const std::string& section, const std::string& key);  // "section.key"
[[noreturn]] void fail(const std::string& source, const std::string& where, const std::string& expectation,
                       const std::string& got);
std::string item(const std::string& key, const std::string& value, const char* unit);  // "key=value unit"
}  // namespace detail

// One setting: its key, the member of C it fills, what it accepts and its unit. reason: why the range is what it
// is, or what a special value means ("< 0 disables the check"), shown in error messages; "" when the range says it.
template <class C>
class Param {
 public:
  // An int or a double.
  template <class N, std::enable_if_t<std::is_same_v<N, int> || std::is_same_v<N, double>, int> = 0>
  Param(const char* key, N C::*member, Range range, const char* unit = "", const char* reason = "")
      : key_(key),
        unit_(unit),
        expectation_(
            detail::number_expectation(std::is_same_v<N, int> ? "an integer" : "a number", range, unit, reason)) {
    read_ = plain_read(member, expectation_);
    validate_ = [member, range](const C& c) { return range.contains(c.*member); };
    value_ = [member](const C& c) { return detail::format_number(c.*member); };
  }
  Param(const char* key, uint32_t C::*member, Id id, const char* reason = "")
      : key_(key), unit_(""), expectation_(detail::id_expectation(id.max, reason)) {
    read_ = [member, id, e = expectation_](const File& f, const std::string& s, const std::string& k, C& c) {
      detail::read_id(f, s, k, id.max, c.*member, e);
    };
    validate_ = [member, id](const C& c) { return c.*member <= id.max; };
    value_ = [member](const C& c) { return detail::format_id(c.*member); };
  }
  // An unsigned 32-bit integer (a seed): a negative value or one above 4294967295 is of the wrong type.
  Param(const char* key, uint32_t C::*member, Range range, const char* unit = "", const char* reason = "")
      : key_(key),
        unit_(unit),
        expectation_(detail::number_expectation("an unsigned 32-bit integer", range, unit, reason)) {
    read_ = [member, e = expectation_](const File& f, const std::string& s, const std::string& k, C& c) {
      detail::read_uint32(f, s, k, c.*member, e);
    };
    validate_ = [member, range](const C& c) { return range.contains(c.*member); };
    value_ = [member](const C& c) { return std::to_string(c.*member); };
  }
  Param(const char* key, uint64_t C::*member, const char* reason = "")
      : key_(key),
        unit_(""),
        expectation_(detail::number_expectation("an unsigned integer", Range::any(), "", reason)) {
    read_ = plain_read(member, expectation_);
    validate_ = [](const C&) { return true; };
    value_ = [member](const C& c) { return std::to_string(c.*member); };
  }
  Param(const char* key, bool C::*member, const char* reason = "")
      : key_(key), unit_(""), expectation_(detail::with_reason("true or false", reason)) {
    read_ = plain_read(member, expectation_);
    validate_ = [](const C&) { return true; };
    value_ = [member](const C& c) { return std::string(c.*member ? "true" : "false"); };
  }
  Param(const char* key, std::string C::*member, Text rule, const char* reason = "")
      : key_(key), unit_(""), expectation_(detail::text_expectation(rule, reason)) {
    read_ = plain_read(member, expectation_);
    validate_ = [member, rule](const C& c) { return rule.accepts(c.*member); };
    value_ = [member](const C& c) { return detail::format_text(c.*member); };
  }
  // `names` must outlive the table (a function-local static, like the table itself).
  template <class E, std::enable_if_t<std::is_enum_v<E>, int> = 0>
  Param(const char* key, E C::*member, const EnumNames<E>& names, const char* reason = "")
      : key_(key), unit_(""), expectation_(detail::enum_expectation(names.list(), reason)) {
    const EnumNames<E>* n = &names;
    read_ = [member, n, e = expectation_](const File& f, const std::string& s, const std::string& k, C& c) {
      std::string text;
      if (f.read(s, k, text, e) && !n->parse(text, c.*member)) {
        detail::fail(f.path(), detail::field(s, k), e, "'" + text + "'");
      }
    };
    validate_ = [](const C&) { return true; };
    value_ = [member, n](const C& c) { return std::string(n->name(c.*member)); };
  }

  const char* key() const { return key_; }
  const char* unit() const { return unit_; }
  // "an odd integer in [1, 11]", "a number in (0, 1] m (0: off)".
  const std::string& expectation() const { return expectation_; }
  // Reads section.key into c (absent: unchanged).
  void read(const File& file, const std::string& section, C& c) const { read_(file, section, key_, c); }
  bool valid(const C& c) const { return validate_(c); }
  std::string value(const C& c) const { return value_(c); }

 private:
  using ReadFn = std::function<void(const File&, const std::string&, const std::string&, C&)>;
  // Reads a type File::read knows into the member.
  template <class T>
  static ReadFn plain_read(T C::*member, std::string expectation) {
    return [member, e = std::move(expectation)](const File& f, const std::string& s, const std::string& k, C& c) {
      f.read(s, k, c.*member, e);
    };
  }

  const char* key_;
  const char* unit_;
  std::string expectation_;
  ReadFn read_;
  std::function<bool(const C&)> validate_;
  std::function<std::string(const C&)> value_;
};

// One section of a file and what reads it (usually Table::reader(): the table bound to the struct it fills).
struct SectionReader {
  std::string section;
  std::function<void(const File&)> read;
};

// Rejects a top-level section the readers do not name, then runs the readers in their order.
void read_sections(const File& file, const std::vector<SectionReader>& sections);

template <class C>
class Table {
 public:
  Table(std::string section, std::initializer_list<Param<C>> params) : section_(std::move(section)), params_(params) {}

  // A rule between settings: when ok(c) is false, InputError(source, "section.key", "expected <expected>, got
  // <key's value>").
  Table& check(const char* key, std::function<bool(const C&)> ok, std::string expected) {
    return check(key, std::move(ok), [expected](const C&) { return expected; });
  }
  Table& check(const char* key, std::function<bool(const C&)> ok, std::function<std::string(const C&)> expected) {
    checks_.push_back(Check{key, std::move(ok), std::move(expected)});
    return *this;
  }
  // The settings of a member struct, written in this table's section (e.g. the daemon's `dds` section: its own
  // `enabled` plus every DdsConfig key), validated with sub's rules under sub's section name. `sub` must outlive
  // this table.
  template <class S>
  Table& include(S C::*member, const Table<S>& sub) {
    const Table<S>* t = &sub;
    Include inc;
    inc.keys = t->keys();
    inc.read = [member, t](const File& f, const std::string& s, C& c) { t->read_values(f, s, c.*member); };
    inc.validate = [member, t](const std::string& source, const C& c) { t->validate(source, c.*member); };
    inc.items = [member, t](const C& c) { return t->items(c.*member); };
    includes_.push_back(std::move(inc));
    return *this;
  }
  // Values derived from several settings, appended to the echo in parentheses.
  Table& summary(std::function<std::string(const C&)> derived) {
    summary_ = std::move(derived);
    return *this;
  }

  const std::string& section() const { return section_; }
  std::vector<std::string> keys() const {
    std::vector<std::string> out;
    for (const Param<C>& p : params_) out.emplace_back(p.key());
    for (const Include& i : includes_) out.insert(out.end(), i.keys.begin(), i.keys.end());
    return out;
  }

  // Reads `section` (default: the table's) of `file` into c: an unknown key is an InputError listing the known
  // ones, an absent key keeps c's value, a value of the wrong type is an InputError. Does not validate.
  void read(const File& file, C& c) const { read(file, section_, c); }
  void read(const File& file, const std::string& section, C& c) const {
    file.check_keys(section, keys());
    read_values(file, section, c);
  }
  // This table reading c, for read_sections(); c and the table must outlive the call.
  SectionReader reader(C& c) const {
    return SectionReader{section_, [this, &c](const File& f) { read(f, c); }};
  }

  // Every range, then every rule between settings; the first that fails is an InputError naming `source`.
  void validate(const std::string& source, const C& c) const {
    for (const Param<C>& p : params_) {
      if (!p.valid(c)) detail::fail(source, detail::field(section_, p.key()), p.expectation(), p.value(c));
    }
    for (const Include& i : includes_) i.validate(source, c);
    for (const Check& k : checks_) {
      if (!k.ok(c)) detail::fail(source, detail::field(section_, k.key), k.expected(c), value_of(k.key, c));
    }
  }

  // "section: key=value unit, ... (summary)".
  std::string describe(const C& c) const {
    std::string line = section_ + ":";
    const std::vector<std::string> all = items(c);
    for (std::size_t i = 0; i < all.size(); ++i) line += (i == 0 ? " " : ", ") + all[i];
    if (summary_) line += " (" + summary_(c) + ")";
    return line;
  }

  // The echo's "key=value unit" items, included tables' too.
  std::vector<std::string> items(const C& c) const {
    std::vector<std::string> out;
    for (const Param<C>& p : params_) out.push_back(detail::item(p.key(), p.value(c), p.unit()));
    for (const Include& i : includes_) {
      const std::vector<std::string> more = i.items(c);
      out.insert(out.end(), more.begin(), more.end());
    }
    return out;
  }
  // Reads the keys without checking for unknown ones (the including table does that).
  void read_values(const File& file, const std::string& section, C& c) const {
    for (const Param<C>& p : params_) p.read(file, section, c);
    for (const Include& i : includes_) i.read(file, section, c);
  }

 private:
  struct Check {
    const char* key;
    std::function<bool(const C&)> ok;
    std::function<std::string(const C&)> expected;
  };
  struct Include {
    std::vector<std::string> keys;
    std::function<void(const File&, const std::string&, C&)> read;
    std::function<void(const std::string&, const C&)> validate;
    std::function<std::vector<std::string>(const C&)> items;
  };

  std::string value_of(const std::string& key, const C& c) const {
    for (const Param<C>& p : params_) {
      if (key == p.key()) return p.value(c);
    }
    return "";
  }

  std::string section_;
  std::vector<Param<C>> params_;
  std::vector<Check> checks_;
  std::vector<Include> includes_;
  std::function<std::string(const C&)> summary_;
};

}  // namespace agvslam::params
