#pragma once
// A SocketCAN raw socket (RAII): non-blocking, bound to one interface, receiving every error frame
// (CAN_RAW_ERR_FILTER = every error class) and the data frames of the ids it is asked to receive (CAN_RAW_FILTER;
// none by default), CAN FD frames enabled on request.
//
// Received frames are stamped with the kernel's receive time (SO_TIMESTAMPNS): the daemon reads them in batches
// once per pose, so the time of reading is up to a pose period late, while the kernel stamp is when the frame
// arrived, and it is CLOCK_REALTIME, the clock of the pose samples' capture time (PoseSample::t_ns).

#include <cstdint>
#include <string>
#include <vector>

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

// A data frame id to receive.
struct CanId {
  uint32_t id = 0;
  bool extended = false;
};

struct ReceivedCanFrame {
  CanFrameBytes frame;
  int64_t t_ns = 0;  // kernel receive time, CLOCK_REALTIME nanoseconds
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
  bool open(const std::string& interface, bool fd_frames, std::string* error, const std::vector<CanId>& receive = {});
  void close();
  bool is_open() const { return fd_ >= 0; }

  SendResult send(const CanFrameBytes& frame, int* err = nullptr);
  // Reads every pending frame without blocking: error frames are added to `counts`, data frames (of the ids asked
  // for) appended to *received when it is given. Returns true when an error frame reported bus-off.
  bool drain(ErrorFrameCounts& counts, std::vector<ReceivedCanFrame>* received = nullptr);

 private:
  int fd_ = -1;
  bool fd_frames_ = false;
};

}  // namespace agvslam::drivers::can
