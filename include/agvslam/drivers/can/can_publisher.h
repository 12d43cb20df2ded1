#pragma once
// The daemon's CAN pose output. publish() is called on the tracker's thread and never blocks: the socket is
// non-blocking, a full interface queue (ENOBUFS/EAGAIN) drops the frame and counts it, and an interface that is
// down, removed, or whose controller went bus-off is closed and reopened with exponential back-off (a reopen
// attempt is a few system calls, made from publish() when its time has come). Error frames are read on every
// publish() and counted. Not thread-safe: call publish() and stats() from one thread (the daemon's output stage).
//
// Input on the same socket: the data frames of the ids given to the constructor (the vehicle's odometry) are read
// without blocking on every publish() and poll() and kept, with their kernel receive time, until
// take_received(); at most kMaxReceivedPending wait (the oldest are dropped and counted). A sample whose
// odometry_check.state is not kOff adds AGVSLAM_ODOM_CHECK to the cycles that carry AGVSLAM_STATUS.

#include <array>
#include <chrono>
#include <cstdint>
#include <string>
#include <vector>

#include "agvslam/drivers/can/can_config.h"
#include "agvslam/drivers/can/can_socket.h"
#include "agvslam/drivers/can/pose_frames.h"
#include "agvslam/drivers/pose_sample.h"

namespace agvslam::drivers::can {

struct CanPublisherStats {
  uint64_t poses_submitted = 0;  // publish() calls
  uint64_t cycles = 0;           // poses due for sending (after rate decimation)
  uint64_t cycles_sent = 0;      // cycles whose frames were all accepted by the socket
  uint64_t frames_sent = 0;
  uint64_t frames_dropped_no_buffer = 0;  // ENOBUFS / EAGAIN
  uint64_t frames_dropped_down = 0;       // interface down / closed
  uint64_t frames_failed = 0;             // other send errors
  uint64_t reopen_attempts = 0;
  uint64_t reopens = 0;                  // successful (re)opens, the first open included
  uint64_t frames_received = 0;          // data frames of the receive ids
  uint64_t frames_received_dropped = 0;  // of which dropped: more than kMaxReceivedPending waited
  ErrorFrameCounts error_frames;
  bool open = false;
};

struct CanPublishResult {
  bool due = false;   // the rate let this pose through
  bool sent = false;  // every frame of the cycle was accepted by the socket
  uint8_t counter = 0;
  int frames_sent = 0;
};

class CanPosePublisher {
 public:
  // Validates the config and tries to open the interface once; a failure is not an error here (the publisher
  // retries with back-off), see is_open() and last_error().
  explicit CanPosePublisher(const CanConfig& config, std::vector<CanId> receive = {});

  CanPublishResult publish(const PoseSample& sample);
  // Reads what arrived (error frames, received frames) and reopens a closed interface when its time has come,
  // without sending anything.
  void poll();
  // The received frames since the last call, oldest first.
  std::vector<ReceivedCanFrame> take_received();
  static constexpr std::size_t kMaxReceivedPending = 4096;

  bool is_open() const { return socket_.is_open(); }
  const std::string& last_error() const { return last_error_; }
  CanPublisherStats stats() const;
  const CanConfig& config() const { return config_; }

 private:
  using Clock = std::chrono::steady_clock;
  bool try_open(Clock::time_point now);
  void read_pending(Clock::time_point now);
  void mark_down(Clock::time_point now, const std::string& why);

  CanConfig config_;
  std::vector<CanId> receive_;
  CanSocket socket_;
  std::vector<ReceivedCanFrame> received_;
  std::string last_error_;
  Clock::time_point next_reopen_{};
  std::chrono::milliseconds backoff_;
  int64_t next_due_t_ns_ = INT64_MIN;
  uint8_t counter_ = 0;
  uint64_t cycle_index_ = 0;
  int last_errno_logged_ = 0;
  std::array<CanFrameBytes, kMaxClassicFrames + 1> frames_{};  // the classic set, then ODOM_CHECK
  CanPublisherStats stats_;
};

}  // namespace agvslam::drivers::can
