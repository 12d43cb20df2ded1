#pragma once
// Wheel odometry in over CAN: the vehicle controller's own odometry message, described by a DBC file, decoded into
// speed and yaw rate (the daemon's `can_odometry` section). By default the message is VEHICLE_ODOMETRY of
// deploy/agvslam.dbc (id base+6, Speed m/s, YawRate deg/s, Counter, Crc as in the pose frames); a vehicle that
// already has an odometry message names its own DBC, message and signals instead. Pure: no socket (the daemon's
// CanPosePublisher receives the frames on its socket, filtered for id()).

#include <cstdint>
#include <optional>
#include <string>

#include "agvslam/core/param_table.h"
#include "agvslam/core/trajectory.h"
#include "agvslam/drivers/can/dbc.h"
#include "agvslam/drivers/can/pose_frames.h"

namespace agvslam::drivers::can {

struct CanOdometryConfig {
  std::string dbc;  // DBC file describing the message (resolved path); required
  std::string message = "VEHICLE_ODOMETRY";
  // The DBC's id is for base id 0x300 and moves with can.base_id and can.extended_ids, as the agvslam frames do
  // (deploy/agvslam.dbc); false: the id and format are the DBC's own (a vehicle's DBC).
  bool relative_to_base_id = true;
  std::string speed_signal = "Speed";       // along base_link x, negative when reversing
  std::string speed_unit;                   // m/s | km/h | cm/s | mm/s; "" = the signal's unit in the DBC
  std::string yaw_rate_signal = "YawRate";  // about base_link z, counter-clockwise positive
  std::string yaw_rate_unit;                // deg/s | rad/s | mrad/s; "" = the signal's unit in the DBC
  std::string counter_signal = "Counter";   // rolling counter; a repeated value is rejected. "" = none
  // CRC-8/SAE-J1850 over the id and the payload but its last byte (the agvslam frames' convention, see
  // pose_frames.h), in the last byte; a mismatch is rejected. "" = the message has no such CRC.
  std::string crc_signal = "Crc";

  // Ranges only (the DBC is checked when CanOdometryDecoder loads it).
  void validate(const std::string& source) const;
  std::string describe() const;
};

// The settings of the `can_odometry` section (every field above, named alike).
const params::Table<CanOdometryConfig>& can_odometry_params();

struct CanOdometryStats {
  uint64_t frames = 0;            // frames with the odometry id handed to decode()
  uint64_t accepted = 0;          // turned into a sample
  uint64_t crc_bad = 0;           // rejected: Crc does not match
  uint64_t counter_repeated = 0;  // rejected: Counter did not advance (a repeated or replayed frame)
  uint64_t counter_gaps = 0;      // accepted, but Counter skipped values (frames lost on the way)
  uint64_t too_short = 0;         // rejected: shorter than the DBC's signals need
};

class CanOdometryDecoder {
 public:
  // Loads config.dbc and finds the message and signals. Throws InputError(config.dbc, ...) for an unreadable or
  // malformed DBC, InputError(source, "can_odometry.<key>", ...) for a message, signal or unit the DBC does not
  // have or this decoder does not know. `layout` is the pose output's (can.base_id, can.extended_ids).
  CanOdometryDecoder(const CanOdometryConfig& config, const FrameLayout& layout, const std::string& source);

  uint32_t id() const { return id_; }  // as received on the bus
  bool extended() const { return extended_; }

  // The sample of a frame with id(), stamped t_ns (the receive time); nullopt when it is rejected (counted).
  std::optional<OdometryRate> decode(const CanFrameBytes& frame, int64_t t_ns);
  // The frame the vehicle controller would send for `rate` (tests and replay senders; the inverse of decode()).
  CanFrameBytes encode(const OdometryRate& rate, uint8_t counter) const;

  const CanOdometryStats& stats() const { return stats_; }
  std::string describe() const;  // "VEHICLE_ODOMETRY id 0x306 (Speed m/s, YawRate deg/s, Counter, Crc)"

 private:
  std::string name_;
  unsigned length_ = 8;  // bytes, as the DBC gives it
  DbcSignal speed_, yaw_rate_;
  std::optional<DbcSignal> counter_, crc_;
  double speed_to_mps_ = 1.0;
  double yaw_rate_to_radps_ = 1.0;
  uint32_t id_ = 0;
  bool extended_ = false;
  std::optional<int64_t> last_counter_;
  CanOdometryStats stats_;
};

}  // namespace agvslam::drivers::can
