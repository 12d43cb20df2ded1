// CAN frames received by the daemon: the vehicle's odometry message (deploy/agvslam.dbc's VEHICLE_ODOMETRY, as
// can_odometry's defaults configure it) decoded from arbitrary frames. Input: 1 byte of flags (extended, fd),
// 1 byte of length, then the payload; consecutive frames in one input exercise the rolling counter.
#include <algorithm>
#include <optional>

#include "agvslam/drivers/can/odometry_input.h"
#include "fuzz_common.h"

#ifndef AGVSLAM_SOURCE_DIR
#error "AGVSLAM_SOURCE_DIR must name the source tree (deploy/agvslam.dbc)"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  using namespace agvslam::drivers::can;
  static const Dbc dbc = Dbc::load(AGVSLAM_SOURCE_DIR "/deploy/agvslam.dbc");
  static const CanOdometryDecoder fresh = [] {
    CanOdometryConfig config;
    config.dbc = AGVSLAM_SOURCE_DIR "/deploy/agvslam.dbc";
    return CanOdometryDecoder(config, FrameLayout{}, "fuzz");
  }();
  CanOdometryDecoder decoder = fresh;  // no counter seen yet
  std::size_t pos = 0;
  int64_t t_ns = 0;
  while (pos + 2 <= size) {
    CanFrameBytes frame;
    const uint8_t flags = data[pos], len = data[pos + 1];
    pos += 2;
    frame.extended = (flags & 1) != 0;
    frame.fd = (flags & 2) != 0;
    frame.id = decoder.id();
    frame.len = static_cast<uint8_t>(std::min<std::size_t>({len, 64, size - pos}));
    std::copy(data + pos, data + pos + frame.len, frame.data.begin());
    pos += frame.len;
    t_ns += 10'000'000;
    decoder.decode(frame, t_ns);
    // Every message of the project's DBC from the same bytes (agvslam-can-decode on a log).
    for (const DbcMessage& m : dbc.messages()) decode_signals(m, frame);
  }
  return 0;
}
