#include "agvslam/drivers/can/odometry_input.h"

#include <cmath>
#include <filesystem>
#include <utility>

#include "agvslam/core/error.h"

namespace agvslam::drivers::can {
namespace {

constexpr uint32_t kDbcBaseId = 0x300;  // the base id deploy/agvslam.dbc's ids are written for

const std::vector<std::pair<std::string, double>>& speed_units() {
  static const std::vector<std::pair<std::string, double>> units = {
      {"m/s", 1.0}, {"km/h", 1.0 / 3.6}, {"cm/s", 1e-2}, {"mm/s", 1e-3}};
  return units;
}

const std::vector<std::pair<std::string, double>>& yaw_rate_units() {
  static const std::vector<std::pair<std::string, double>> units = {
      {"deg/s", M_PI / 180.0}, {"rad/s", 1.0}, {"mrad/s", 1e-3}};
  return units;
}

std::vector<std::string> unit_names(const std::vector<std::pair<std::string, double>>& units, bool with_empty) {
  std::vector<std::string> names;
  if (with_empty) names.emplace_back();
  for (const auto& u : units) names.push_back(u.first);
  return names;
}

std::string joined(const std::vector<std::string>& names) {
  std::string out;
  for (const auto& n : names) out += (out.empty() ? "" : ", ") + n;
  return out;
}

std::string signal_names(const DbcMessage& m) {
  std::vector<std::string> names;
  for (const auto& s : m.signals) names.push_back(s.name);
  return joined(names);
}

// The factor to SI of `key`'s unit (the configured one, else the DBC's).
double unit_factor(const std::vector<std::pair<std::string, double>>& units, const std::string& configured,
                   const DbcSignal& signal, const std::string& source, const std::string& key) {
  const std::string& unit = configured.empty() ? signal.unit : configured;
  for (const auto& u : units) {
    if (u.first == unit) return u.second;
  }
  throw InputError(source, "can_odometry." + key,
                   "expected one of " + joined(unit_names(units, false)) + " (signal " + signal.name +
                       " has the unit '" + signal.unit + "' in the DBC: name its unit here)");
}

}  // namespace

const params::Table<CanOdometryConfig>& can_odometry_params() {
  using C = CanOdometryConfig;
  using params::Text;
  static const params::Table<C> table(
      "can_odometry",
      {
          {"dbc", &C::dbc, Text::non_empty(), "the DBC file that describes the odometry message"},
          {"message", &C::message, Text::non_empty(), "a message name of the DBC"},
          {"relative_to_base_id", &C::relative_to_base_id,
           "true: the DBC's id is for base id 0x300 and moves with can.base_id (deploy/agvslam.dbc)"},
          {"speed_signal", &C::speed_signal, Text::non_empty(), "a signal of the message"},
          {"speed_unit", &C::speed_unit, Text::one_of(unit_names(speed_units(), true)), "\"\" = the DBC's unit"},
          {"yaw_rate_signal", &C::yaw_rate_signal, Text::non_empty(), "a signal of the message"},
          {"yaw_rate_unit", &C::yaw_rate_unit, Text::one_of(unit_names(yaw_rate_units(), true)),
           "\"\" = the DBC's unit"},
          {"counter_signal", &C::counter_signal, Text::any(), "a signal of the message, \"\" = none"},
          {"crc_signal", &C::crc_signal, Text::any(), "a signal of the message, \"\" = none"},
      });
  return table;
}

void CanOdometryConfig::validate(const std::string& source) const { can_odometry_params().validate(source, *this); }

std::string CanOdometryConfig::describe() const { return can_odometry_params().describe(*this); }

CanOdometryDecoder::CanOdometryDecoder(const CanOdometryConfig& config, const FrameLayout& layout,
                                       const std::string& source) {
  config.validate(source);
  if (!std::filesystem::is_regular_file(config.dbc)) {
    throw InputError(source, "can_odometry.dbc", "expected an existing DBC file (" + config.dbc + " does not exist)");
  }
  const Dbc dbc = Dbc::load(config.dbc);
  const DbcMessage* m = dbc.find(config.message);
  if (m == nullptr) {
    std::vector<std::string> names;
    for (const auto& msg : dbc.messages()) names.push_back(msg.name);
    throw InputError(source, "can_odometry.message",
                     "expected a message of " + config.dbc + " (it has " + joined(names) + "), got " + config.message);
  }
  name_ = m->name;
  length_ = m->length;
  const auto find = [&](const std::string& key, const std::string& name) -> std::optional<DbcSignal> {
    if (name.empty()) return std::nullopt;
    const DbcSignal* s = m->signal(name);
    if (s == nullptr) {
      throw InputError(
          source, "can_odometry." + key,
          "expected a signal of " + m->name + " in " + config.dbc + " (" + signal_names(*m) + "), got " + name);
    }
    return *s;
  };
  speed_ = *find("speed_signal", config.speed_signal);
  yaw_rate_ = *find("yaw_rate_signal", config.yaw_rate_signal);
  counter_ = find("counter_signal", config.counter_signal);
  crc_ = find("crc_signal", config.crc_signal);
  if (crc_ && !(crc_->little_endian && crc_->length == 8 && crc_->start_bit == 8 * (m->length - 1))) {
    throw InputError(source, "can_odometry.crc_signal",
                     "expected an 8-bit signal in the message's last byte (CRC-8/SAE-J1850 as in the agvslam frames)");
  }
  speed_to_mps_ = unit_factor(speed_units(), config.speed_unit, speed_, source, "speed_unit");
  yaw_rate_to_radps_ = unit_factor(yaw_rate_units(), config.yaw_rate_unit, yaw_rate_, source, "yaw_rate_unit");
  if (config.relative_to_base_id) {
    if (m->id < kDbcBaseId) {
      throw InputError(source, "can_odometry.relative_to_base_id",
                       "false for a DBC whose ids are not written for base id 0x300 (" + m->name + " has id " +
                           std::to_string(m->id) + ")");
    }
    id_ = layout.base_id + (m->id - kDbcBaseId);
    extended_ = layout.extended_ids;
  } else {
    id_ = m->id;
    extended_ = m->extended;
  }
  if (id_ > (extended_ ? 0x1FFFFFFFU : 0x7FFU)) {
    throw InputError(
        source, "can_odometry.message",
        "expected an id that fits the frame format (" + m->name + " lands on " + std::to_string(id_) + ")");
  }
  for (uint32_t offset = kPoseXYawOffset; offset <= kPoseFdOffset; ++offset) {
    if (offset == kVehicleOdometryOffset) continue;
    if (id_ == layout.base_id + offset && extended_ == layout.extended_ids) {
      throw InputError(source, "can_odometry.message",
                       "a message whose id is not one the pose output sends (" + m->name + " lands on base_id + " +
                           std::to_string(offset) + ")");
    }
  }
}

std::optional<OdometryRate> CanOdometryDecoder::decode(const CanFrameBytes& frame, int64_t t_ns) {
  ++stats_.frames;
  const auto speed_raw = speed_.raw(frame.data.data(), frame.len);
  const auto yaw_raw = yaw_rate_.raw(frame.data.data(), frame.len);
  if (!speed_raw || !yaw_raw) {
    ++stats_.too_short;
    return std::nullopt;
  }
  if (crc_) {
    if (frame.len != length_ || frame_crc(frame) != frame.data[frame.len - 1U]) {
      ++stats_.crc_bad;
      return std::nullopt;
    }
  }
  if (counter_) {
    const auto c = counter_->raw(frame.data.data(), frame.len);
    if (!c) {
      ++stats_.too_short;
      return std::nullopt;
    }
    if (last_counter_) {
      if (*c == *last_counter_) {
        ++stats_.counter_repeated;
        return std::nullopt;
      }
      const int64_t modulo = int64_t{1} << counter_->length;
      if (*c != (*last_counter_ + 1) % modulo) ++stats_.counter_gaps;
    }
    last_counter_ = *c;
  }
  ++stats_.accepted;
  OdometryRate r;
  r.t_ns = t_ns;
  r.speed_mps = speed_.physical(*speed_raw) * speed_to_mps_;
  r.yaw_rate_radps = yaw_rate_.physical(*yaw_raw) * yaw_rate_to_radps_;
  return r;
}

CanFrameBytes CanOdometryDecoder::encode(const OdometryRate& rate, uint8_t counter) const {
  CanFrameBytes f;
  f.id = id_;
  f.extended = extended_;
  f.len = static_cast<uint8_t>(length_);
  speed_.encode(rate.speed_mps / speed_to_mps_, f.data.data());
  yaw_rate_.encode(rate.yaw_rate_radps / yaw_rate_to_radps_, f.data.data());
  if (counter_) counter_->encode(counter % (1U << counter_->length), f.data.data());
  if (crc_) f.data[f.len - 1U] = frame_crc(f);
  return f;
}

std::string CanOdometryDecoder::describe() const {
  char id[16];
  std::snprintf(id, sizeof id, extended_ ? "0x%08X" : "0x%03X", id_);
  std::string s = name_ + " id " + id + " (" + speed_.name + " x" + std::to_string(speed_to_mps_) + " -> m/s, " +
                  yaw_rate_.name + " x" + std::to_string(yaw_rate_to_radps_) + " -> rad/s";
  if (counter_) s += ", " + counter_->name;
  if (crc_) s += ", " + crc_->name;
  return s + ")";
}

}  // namespace agvslam::drivers::can
