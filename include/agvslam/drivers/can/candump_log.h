#pragma once
// candump -L log lines (can-utils' log format, also read by canplayer):
//   (1699999999.123456) vcan0 300#0102030405060708      classic frame, 3 hex digits: 11-bit id
//   (1699999999.123456) vcan0 12345678#0102             8 hex digits: 29-bit id (or an error frame, flag 0x20000000)
//   (1699999999.123456) vcan0 308##1<up to 64 bytes>    CAN FD frame, the nibble after ## holds its flags
//   (1699999999.123456) vcan0 123#R                     remote frame

#include <cstdint>
#include <optional>
#include <string>

#include "agvslam/drivers/can/pose_frames.h"

namespace agvslam::drivers::can {

struct CandumpRecord {
  int64_t t_ns = 0;  // the log's time stamp
  std::string interface;
  CanFrameBytes frame;
  bool error_frame = false;  // CAN_ERR_FLAG set (frame.id then holds the error class bits)
  bool remote = false;
  uint8_t fd_flags = 0;
};

// Parses one line; nullopt for an empty line or a comment. Throws InputError(source, "line N", ...) for a line
// that is not in the format above.
std::optional<CandumpRecord> parse_candump_line(const std::string& line, const std::string& source, int line_no);
// The line candump -L would print for a frame (time in seconds with 6 decimals).
std::string format_candump_line(const CanFrameBytes& frame, const std::string& interface, int64_t t_ns);

}  // namespace agvslam::drivers::can
