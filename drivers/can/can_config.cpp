#include "agvslam/drivers/can/can_config.h"

#include <net/if.h>

namespace agvslam::drivers::can {

const params::Table<CanConfig>& can_params() {
  using params::Range;
  static const params::Table<CanConfig> table =
      params::Table<CanConfig>(
          "can",
          {
              {"interface", &CanConfig::interface, params::Text::length(1, IFNAMSIZ - 1),
               "a network interface name such as can0"},
              {"base_id", &CanConfig::base_id, params::Id{0x1FFFFFFF}, "the frames use base_id .. base_id + 8"},
              {"extended_ids", &CanConfig::extended_ids},
              {"fd", &CanConfig::fd},
              {"rate_hz", &CanConfig::rate_hz, Range::closed(0, 1000), "Hz", "0: every pose"},
              {"send_velocity", &CanConfig::send_velocity},
              {"send_stddev", &CanConfig::send_stddev},
              {"status_every", &CanConfig::status_every, Range::closed(1, 1000), "cycles"},
              {"reopen_min_ms", &CanConfig::reopen_min_ms, Range::closed(1, 60000), "ms"},
              {"reopen_max_ms", &CanConfig::reopen_max_ms, Range::at_most(600000), "ms"},
          })
          .check(
              "base_id",
              [](const CanConfig& c) { return c.base_id + kPoseFdOffset <= (c.extended_ids ? 0x1FFFFFFFU : 0x7FFU); },
              [](const CanConfig& c) {
                return std::string("an id with base_id + 8 <= ") + (c.extended_ids ? "0x1FFFFFFF" : "0x7FF") +
                       (c.extended_ids ? "" : " (11-bit ids; set can.extended_ids for 29-bit ids)");
              })
          .check(
              "reopen_max_ms", [](const CanConfig& c) { return c.reopen_max_ms >= c.reopen_min_ms; },
              "at least reopen_min_ms");
  return table;
}

void CanConfig::validate(const std::string& source) const { can_params().validate(source, *this); }

std::string CanConfig::describe() const { return can_params().describe(*this); }

}  // namespace agvslam::drivers::can
