#pragma once
// Configuration of the SocketCAN pose output (the daemon reads it from its YAML file, section `can`).

#include <cstdint>
#include <string>

#include "agvslam/core/param_table.h"
#include "agvslam/drivers/can/pose_frames.h"

namespace agvslam::drivers::can {

struct CanConfig {
  std::string interface = "can0";  // SocketCAN network interface (can0, vcan0, slcan0, ...)
  // Id of the first frame; the others follow at fixed offsets (deploy/agvslam.dbc uses 0x300: shift its BO_ ids
  // by the same amount when you change this).
  uint32_t base_id = 0x300;
  bool extended_ids = false;  // 29-bit identifiers
  bool fd = false;            // send the single 48-byte CAN FD frame (base+8) instead of the classic frames
  // Highest pose rate on the bus (poses arriving faster are decimated by capture time); 0: every pose.
  double rate_hz = 20.0;
  bool send_velocity = true;  // classic: AGVSLAM_VELOCITY in every cycle
  bool send_stddev = true;    // classic: AGVSLAM_POSE_STDDEV in every cycle
  int status_every = 1;       // classic: AGVSLAM_STATUS every N-th cycle
  // Reopening after the interface went down, was removed, or the controller went bus-off: first retry after
  // reopen_min_ms, then doubling up to reopen_max_ms.
  int reopen_min_ms = 100;
  int reopen_max_ms = 5000;

  FrameLayout layout() const { return FrameLayout{base_id, extended_ids}; }
  // Throws InputError(source, "can.<key>", "expected ...").
  void validate(const std::string& source) const;
  std::string describe() const;
};

// The settings of the `can` section (every field above, named alike; base_id as 0x300 or 768).
const params::Table<CanConfig>& can_params();

}  // namespace agvslam::drivers::can
