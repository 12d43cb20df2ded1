#include "agvslam/drivers/can/dbc.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <regex>
#include <sstream>

#include "agvslam/core/error.h"

namespace agvslam::drivers::can {
namespace {

constexpr uint32_t kDbcExtendedFlag = 0x80000000U;

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return {};
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

bool starts_with(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

}  // namespace

std::optional<int64_t> DbcSignal::raw(const uint8_t* data, std::size_t len) const {
  uint64_t v = 0;
  if (little_endian) {
    if (start_bit + length > len * 8) return std::nullopt;
    v = get_bits_le(data, start_bit, length);
  } else {
    // Motorola: start_bit is the MSB; walk down within a byte (7..0), then to bit 7 of the next byte.
    unsigned bit = start_bit;
    for (unsigned i = 0; i < length; ++i) {
      if (bit / 8 >= len) return std::nullopt;
      v = (v << 1) | ((data[bit / 8] >> (bit % 8)) & 1U);
      bit = (bit % 8 == 0) ? bit + 15 : bit - 1;
    }
  }
  if (is_signed && length < 64 && ((v >> (length - 1)) & 1U) != 0) v |= ~((1ULL << length) - 1);
  return static_cast<int64_t>(v);
}

void DbcSignal::encode(double physical_value, uint8_t* data) const {
  const double lo = is_signed ? -std::ldexp(1.0, static_cast<int>(length) - 1) : 0.0;
  const double hi =
      is_signed ? std::ldexp(1.0, static_cast<int>(length) - 1) - 1 : std::ldexp(1.0, static_cast<int>(length)) - 1;
  double q = factor != 0.0 ? std::round((physical_value - offset) / factor) : 0.0;
  if (std::isnan(q)) q = 0.0;
  q = std::clamp(q, lo, hi);
  const uint64_t mask = length >= 64 ? ~0ULL : ((1ULL << length) - 1);
  const uint64_t v = static_cast<uint64_t>(static_cast<int64_t>(q)) & mask;
  if (little_endian) {
    put_bits_le(data, start_bit, length, v);
    return;
  }
  // Motorola: the same walk as raw(), MSB first.
  unsigned bit = start_bit;
  for (unsigned i = 0; i < length; ++i) {
    const auto m = static_cast<uint8_t>(1U << (bit % 8));
    const bool set = ((v >> (length - 1 - i)) & 1U) != 0;
    data[bit / 8] = static_cast<uint8_t>(set ? (data[bit / 8] | m) : (data[bit / 8] & ~m));
    bit = (bit % 8 == 0) ? bit + 15 : bit - 1;
  }
}

const DbcSignal* DbcMessage::signal(const std::string& signal_name) const {
  for (const auto& s : signals) {
    if (s.name == signal_name) return &s;
  }
  return nullptr;
}

Dbc Dbc::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "file", "expected a readable DBC file");
  std::ostringstream text;
  text << in.rdbuf();
  return parse(text.str(), path);
}

Dbc Dbc::parse(const std::string& text, const std::string& source) {
  // BO_ <id> <name>: <len> <transmitter>
  static const std::regex bo_re(R"(^BO_\s+(\d+)\s+([A-Za-z_][A-Za-z0-9_]*)\s*:\s*(\d+)\s+(\S+)\s*$)");
  // SG_ <name> [mux] : <start>|<len>@<order><sign> (<factor>,<offset>) [<min>|<max>] "<unit>" <receivers>
  static const std::regex sg_re(
      R"re(^SG_\s+([A-Za-z_][A-Za-z0-9_]*)\s*(\S*)\s*:\s*(\d+)\|(\d+)@([01])([+-])\s*\(\s*([^,\s]+)\s*,\s*([^)\s]+)\s*\)\s*\[\s*([^|\s]+)\s*\|\s*([^\]\s]+)\s*\]\s*"([^"]*)"(.*)$)re");
  static const std::regex val_re(R"(^VAL_\s+(\d+)\s+([A-Za-z_][A-Za-z0-9_]*)\s+(.*);\s*$)");
  static const std::regex val_item_re(R"re((-?\d+)\s+"([^"]*)")re");
  static const std::regex ba_fmt_re(R"(^BA_\s+"VFrameFormat"\s+BO_\s+(\d+)\s+(\d+)\s*;\s*$)");

  Dbc dbc;
  std::istringstream lines(text);
  std::string line;
  int line_no = 0;
  DbcMessage* current = nullptr;
  auto where = [&] { return "line " + std::to_string(line_no); };
  auto number = [&](const std::string& s) {
    try {
      std::size_t used = 0;
      const double v = std::stod(s, &used);
      if (used != s.size()) throw std::invalid_argument(s);
      return v;
    } catch (const std::exception&) {
      throw InputError(source, where(), "expected a number, found '" + s + "'");
    }
  };
  // The regular expressions admit any run of digits: values beyond the field's range are refused here (std::stoul
  // would throw out_of_range, a cast would truncate).
  auto integer = [&](const std::string& s, uint64_t max) {
    uint64_t v = 0;
    try {
      v = std::stoull(s);
    } catch (const std::exception&) {
      v = max + 1;
    }
    if (v > max) {
      throw InputError(source, where(), "expected an integer in [0, " + std::to_string(max) + "], found '" + s + "'");
    }
    return v;
  };
  auto signed_integer = [&](const std::string& s) {
    try {
      return static_cast<int64_t>(std::stoll(s));
    } catch (const std::exception&) {
      throw InputError(source, where(), "expected a 64-bit integer, found '" + s + "'");
    }
  };
  constexpr uint64_t kMaxRawId = 0xFFFFFFFF;  // 29-bit id | kDbcExtendedFlag
  std::smatch m;
  while (std::getline(lines, line)) {
    ++line_no;
    const std::string t = trim(line);
    if (starts_with(t, "BO_ ")) {
      if (!std::regex_match(t, m, bo_re))
        throw InputError(source, where(), "expected 'BO_ <id> <name>: <length> <node>'");
      DbcMessage msg;
      const auto raw_id = static_cast<uint32_t>(integer(m[1].str(), kMaxRawId));
      msg.extended = (raw_id & kDbcExtendedFlag) != 0;
      msg.id = raw_id & ~kDbcExtendedFlag;
      msg.name = m[2].str();
      msg.length = static_cast<unsigned>(integer(m[3].str(), 64));
      msg.transmitter = m[4].str();
      dbc.messages_.push_back(msg);
      current = &dbc.messages_.back();
    } else if (starts_with(t, "SG_ ")) {
      if (current == nullptr) throw InputError(source, where(), "expected SG_ lines after a BO_ line");
      if (!std::regex_match(t, m, sg_re)) {
        throw InputError(source, where(),
                         "expected 'SG_ <name> : <start>|<length>@<0|1><+|-> (<factor>,<offset>) [<min>|<max>] "
                         "\"<unit>\" <receivers>'");
      }
      if (!m[2].str().empty()) {
        throw InputError(source, where(), "expected a plain signal (multiplexed signals are not supported)");
      }
      DbcSignal s;
      s.name = m[1].str();
      s.start_bit = static_cast<unsigned>(integer(m[3].str(), 64 * 8 - 1));
      s.length = static_cast<unsigned>(integer(m[4].str(), 64));
      s.little_endian = m[5].str() == "1";
      s.is_signed = m[6].str() == "-";
      s.factor = number(m[7].str());
      s.offset = number(m[8].str());
      s.minimum = number(m[9].str());
      s.maximum = number(m[10].str());
      s.unit = m[11].str();
      if (s.length == 0 || s.length > 64) throw InputError(source, where(), "expected a signal length of 1..64 bits");
      if (s.little_endian && s.start_bit + s.length > current->length * 8) {
        throw InputError(
            source, where(),
            "expected signal " + s.name + " to fit in the message's " + std::to_string(current->length) + " bytes");
      }
      current->signals.push_back(s);
    } else {
      if (!t.empty() && !starts_with(t, "SG_")) current = nullptr;
      if (starts_with(t, "VAL_ ") && std::regex_match(t, m, val_re)) {
        const auto raw_id = static_cast<uint32_t>(integer(m[1].str(), kMaxRawId));
        const std::string sig = m[2].str();
        const std::string items = m[3].str();
        for (auto& msg : dbc.messages_) {
          if (msg.id != (raw_id & ~kDbcExtendedFlag) || msg.extended != ((raw_id & kDbcExtendedFlag) != 0)) continue;
          for (auto& s : msg.signals) {
            if (s.name != sig) continue;
            for (auto it = std::sregex_iterator(items.begin(), items.end(), val_item_re); it != std::sregex_iterator();
                 ++it) {
              s.value_names[signed_integer((*it)[1].str())] = (*it)[2].str();
            }
          }
        }
      } else if (starts_with(t, "BA_ \"VFrameFormat\"") && std::regex_match(t, m, ba_fmt_re)) {
        const auto raw_id = static_cast<uint32_t>(integer(m[1].str(), kMaxRawId));
        const auto fmt = integer(m[2].str(), kMaxRawId);
        for (auto& msg : dbc.messages_) {
          if (msg.id == (raw_id & ~kDbcExtendedFlag) && msg.extended == ((raw_id & kDbcExtendedFlag) != 0)) {
            msg.fd = fmt == 14 || fmt == 15;
          }
        }
      }
    }
  }
  return dbc;
}

const DbcMessage* Dbc::find(uint32_t id, bool extended) const {
  for (const auto& m : messages_) {
    if (m.id == id && m.extended == extended) return &m;
  }
  return nullptr;
}

const DbcMessage* Dbc::find(const std::string& name) const {
  for (const auto& m : messages_) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

std::map<std::string, double> decode_signals(const DbcMessage& msg, const CanFrameBytes& f) {
  std::map<std::string, double> out;
  for (const auto& s : msg.signals) {
    if (auto r = s.raw(f.data.data(), f.len)) out[s.name] = s.physical(*r);
  }
  return out;
}

}  // namespace agvslam::drivers::can
