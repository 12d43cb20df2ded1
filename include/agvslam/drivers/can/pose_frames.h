#pragma once
// The CAN frame layout of the pose output (deploy/agvslam.dbc is the authoritative description; keep both in
// step). Pure functions: no socket, so they are tested on any host.
//
// Classic CAN, 8 bytes each, ids relative to a configurable base id (default 0x300), all signals little-endian
// (Intel, DBC "@1"), signed values two's complement:
//   base+0 AGVSLAM_POSE_XYAW   PoseX int32 mm | PoseYaw int16 0.01 deg | TrackingState 4 bit | Counter | Crc
//   base+1 AGVSLAM_POSE_YZ     PoseY int32 mm | PoseZ int16 mm | MapId 4 bit (low bits) | Counter | Crc
//   base+2 AGVSLAM_VELOCITY    VelX int16 mm/s | VelY int16 mm/s | YawRate int16 0.01 deg/s | reserved | Counter | Crc
//   base+3 AGVSLAM_POSE_STDDEV StdDevX uint16 mm | StdDevY uint16 mm | StdDevYaw uint16 0.01 deg | reserved | Counter |
//   Crc base+4 AGVSLAM_STATUS      LatencyMs uint16 0.1 ms | Fps uint8 0.5 Hz | DynamicPct uint8 0.5 % |
//                              DroppedFrames uint16 | TrackingState 4 bit | Counter | Crc
//   base+5 AGVSLAM_ODOM_CHECK  DistanceRatio uint16 0.001 (0xFFFF: not available) | SpeedRmse uint16 mm/s |
//                              HeadingDiff int16 0.01 deg | OdomCheckState 4 bit | Counter | Crc
//                              (with STATUS, only while an odometry input is configured)
//   base+6 VEHICLE_ODOMETRY    in: Speed int16 mm/s | YawRate int16 0.01 deg/s | reserved | Counter | Crc, sent by
//                              the vehicle controller (drivers/can/odometry_input.h decodes it with the DBC)
// Every frame: bits 52..55 Counter (4-bit rolling counter, the same value in every frame of one pose, +1 per
// pose), bits 56..63 Crc (CRC-8/SAE-J1850: poly 0x1D, init 0xFF, final xor 0xFF) over the 4 bytes of the CAN id
// (little-endian, without EFF/RTR/ERR flags) followed by payload bytes 0..len-2.
// CAN FD (optional, instead of the classic set): base+8 AGVSLAM_POSE_FD, 48 bytes, everything in one frame (see
// the DBC for its byte map; MapId there has 16 bits).
// MapId: the SLAM map the pose is in (PoseSample::map_id); it changes when a long loss started a new map, whose
// origin is elsewhere: the vehicle must not join poses of different MapId (4 bits on classic CAN: a change is what
// it reads, and 16 new maps between two frames it receives do not happen).
// Pose = T_map_base (REP-105 map frame, base_link); yaw = atan2(R10, R00) in (-180, 180] degrees; velocities in
// base_link axes; StdDev = sqrt of the covariance diagonal. Values are rounded to the nearest step and saturate
// at the signal's range.

#include <array>
#include <cstddef>
#include <cstdint>

#include "agvslam/drivers/pose_sample.h"

namespace agvslam::drivers::can {

enum FrameOffset : uint32_t {
  kPoseXYawOffset = 0,
  kPoseYZOffset = 1,
  kVelocityOffset = 2,
  kStdDevOffset = 3,
  kStatusOffset = 4,
  kOdometryCheckOffset = 5,
  kVehicleOdometryOffset = 6,
  kPoseFdOffset = 8,
};
inline constexpr std::size_t kPoseFdLength = 48;
inline constexpr std::size_t kMaxClassicFrames = 5;

// A frame as the driver hands it to the socket (and as a candump log line describes it).
struct CanFrameBytes {
  uint32_t id = 0;        // 11-bit or 29-bit identifier, no flags
  bool extended = false;  // 29-bit identifier
  bool fd = false;        // CAN FD frame (len up to 64)
  uint8_t len = 0;
  std::array<uint8_t, 64> data{};
};

struct FrameLayout {
  uint32_t base_id = 0x300;
  bool extended_ids = false;
};

// CRC-8/SAE-J1850 (check value 0x4B for "123456789").
uint8_t crc8_sae_j1850(const uint8_t* data, std::size_t n, uint8_t crc = 0xFF);
// The checksum a frame carries in its last byte (see above).
uint8_t frame_crc(const CanFrameBytes& f);

// Writes the classic frames of one pose cycle into out[] and returns how many: POSE_XYAW, POSE_YZ, then
// VELOCITY and POSE_STDDEV when requested, then STATUS when with_status.
std::size_t encode_classic_frames(const PoseSample& s, uint8_t counter, const FrameLayout& layout, bool with_velocity,
                                  bool with_stddev, bool with_status,
                                  std::array<CanFrameBytes, kMaxClassicFrames>& out);
// AGVSLAM_ODOM_CHECK of one pose cycle (classic, 8 bytes, also sent beside the CAN FD frame).
CanFrameBytes encode_odometry_check_frame(const OdometryCheck& check, uint8_t counter, const FrameLayout& layout);
// The single CAN FD frame of one pose cycle.
CanFrameBytes encode_fd_frame(const PoseSample& s, uint8_t counter, const FrameLayout& layout);

// Little-endian (Intel) bit-field access, start bit numbered as in DBC "@1" (bit 0 = LSB of byte 0).
void put_bits_le(uint8_t* data, unsigned start_bit, unsigned length, uint64_t raw);
uint64_t get_bits_le(const uint8_t* data, unsigned start_bit, unsigned length);

}  // namespace agvslam::drivers::can
