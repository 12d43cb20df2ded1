#pragma once
// A SocketCAN raw socket (RAII): non-blocking, bound to one interface, receiving only error frames
// (CAN_RAW_ERR_FILTER = every error class; no data frames), CAN FD frames enabled on request.

#include <cstdint>
#include <string>

#include "agvslam/drivers/can/pose_frames.h"

namespace agvslam::drivers::can {

enum class SendResult {
  kSent,
  kNoBuffer,  // EAGAIN / ENOBUFS: the interface queue is full; the frame was dropped, nothing blocked
  kDown,      // ENETDOWN / ENXIO / ENODEV / EBADF...: the interface is down or gone; reopen later
  kError,     // any other error (e.g. EINVAL for an FD frame on a classic interface)
};

struct ErrorFrameCounts {
  uint64_t total = 0;
  uint64_t bus_off = 0;
  uint64_t controller = 0;  // error warning / passive, overflow
  uint64_t restarted = 0;
  uint64_t no_ack = 0;
  uint64_t tx_timeout = 0;
  uint64_t other = 0;
};

class CanSocket {
 public:
  CanSocket() = default;
  ~CanSocket() { close(); }
  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;

  // Opens and binds a socket on `interface`. On failure returns false and leaves a message naming the interface
  // and the failing call in *error (e.g. "vcan0: socket(PF_CAN): Address family not supported by protocol").
  // An interface that exists but is down is a failure too (nothing could be sent).
  bool open(const std::string& interface, bool fd_frames, std::string* error);
  void close();
  bool is_open() const { return fd_ >= 0; }

  SendResult send(const CanFrameBytes& frame, int* err = nullptr);
  // Reads every pending error frame without blocking and adds them to `counts`; returns true when one of them
  // reported bus-off.
  bool drain_error_frames(ErrorFrameCounts& counts);

 private:
  int fd_ = -1;
  bool fd_frames_ = false;
};

}  // namespace agvslam::drivers::can
