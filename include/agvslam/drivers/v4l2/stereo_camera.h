#pragma once
// The V4L2 stereo camera: two devices paired by time stamp, or one side-by-side device, delivering
// agvslam::StereoFrame (raw images: the caller rectifies with StereoCalibration::rectify when needed).
//
// Clock: StereoFrame::t_ns is the CLOCK_MONOTONIC capture time of the left image in ns, as the V4L2 driver
// stamped the buffer (UVC: start of exposure or end of frame, per driver). CaptureInfo carries both eyes' stamps
// and realtime_minus_monotonic_ns (CLOCK_REALTIME - CLOCK_MONOTONIC sampled at dequeue) to turn it into wall time.
//
// Never blocks longer than the timeout given to grab(). A device that fails (ENODEV, EIO, node removed,
// stalled for stall_timeout_ms) is closed and reopened with exponential back-off while grab() keeps returning
// (kNoFrame) within its timeout, so a daemon keeps publishing its state. Counters say what was lost.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "agvslam/core/stereo_frame.h"
#include "agvslam/drivers/v4l2/camera_config.h"
#include "agvslam/drivers/v4l2/pairing.h"

namespace agvslam::drivers::v4l2 {

class V4l2Device;

struct CaptureInfo {
  int64_t t_left_ns = 0, t_right_ns = 0;  // CLOCK_MONOTONIC stamps (side by side: equal)
  uint32_t sequence_left = 0, sequence_right = 0;
  int64_t realtime_minus_monotonic_ns = 0;
  int64_t dequeued_ns = 0;  // CLOCK_MONOTONIC when the pair was complete (latency = dequeued_ns - t_ns)
};

struct CaptureStats {
  enum class State { kClosed, kStreaming, kReopening };
  State state = State::kClosed;
  uint64_t frames = 0;        // pairs delivered
  uint64_t dropped_left = 0;  // frames the device skipped (gaps in buffer sequence numbers)
  uint64_t dropped_right = 0;
  uint64_t unpaired_left = 0;  // frames thrown away for want of a partner within the tolerance
  uint64_t unpaired_right = 0;
  uint64_t corrupt = 0;          // buffers flagged V4L2_BUF_FLAG_ERROR (dropped)
  uint64_t device_losses = 0;    // times a streaming camera was lost (error or stall)
  uint64_t reopen_attempts = 0;  // failed reopen attempts
  uint64_t reopens = 0;          // successful reopens after a loss
  std::string last_error;        // the last device error, naming the device
};
const char* to_string(CaptureStats::State s);

class StereoCamera {
 public:
  explicit StereoCamera(V4l2CameraConfig config);  // validates; no I/O
  ~StereoCamera();
  StereoCamera(const StereoCamera&) = delete;
  StereoCamera& operator=(const StereoCamera&) = delete;

  // Opens the device(s) now. With throw_on_failure, any failure throws V4l2Error (start-up: a wrong device,
  // format or size should stop the program with a clear message); without, the camera goes to kReopening and
  // grab() keeps trying with back-off.
  void open(bool throw_on_failure = true);
  void close();

  enum class Grab { kFrame, kNoFrame };
  // Waits at most timeout_ms for the next pair. kFrame fills `frame` (index counts delivered pairs, t_ns as
  // above, left/right CV_8UC1 of width x height) and `info`. The images are handed over without a copy; the
  // camera reuses a buffer only once the caller has released it (else it allocates a new one).
  Grab grab(StereoFrame& frame, int timeout_ms, CaptureInfo* info = nullptr);

  const CaptureStats& stats() const { return stats_; }
  const V4l2CameraConfig& config() const { return config_; }
  // One line: state and counters, for the daemon's status.
  std::string stats_line() const;

 private:
  struct Eye;
  void open_devices();
  void lose(const std::string& why);
  bool try_reopen();
  bool read_eye(int eye, std::deque<int>& released);
  int free_slot(int eye);

  V4l2CameraConfig config_;
  CaptureStats stats_;
  std::vector<std::unique_ptr<Eye>> eyes_;  // one (side by side) or two devices
  TimestampPairer pairer_;
  std::deque<int> released_;
  int64_t next_reopen_ns_ = 0;
  int backoff_ms_ = 0;
  bool ever_opened_ = false;
  cv::Mat sbs_grey_;  // side by side: the whole image before the split
  std::vector<cv::Mat> left_pool_, right_pool_;
  std::vector<bool> left_busy_, right_busy_;
};

int64_t monotonic_now_ns();
int64_t realtime_now_ns();

}  // namespace agvslam::drivers::v4l2
