#pragma once
// Where agvslamd's frames come from: the V4L2 stereo camera (drivers/v4l2) or a dataset folder played like a
// camera. Both deliver rectified grey pairs with a capture time stamp on CLOCK_REALTIME (the clock of ROS stamps
// and of PoseSample::t_ns).
//
//   V4L2     the driver's CLOCK_MONOTONIC buffer stamp converted with the realtime-monotonic offset sampled at
//            dequeue; raw images are rectified with the calibration's maps (into reused buffers).
//   dataset  frame k is decoded (and rectified) ahead of time, then released at its due time on an absolute
//            schedule (rate x the dataset's rate, or rate_hz); its capture stamp is CLOCK_REALTIME at release,
//            as if the camera had just delivered it. rate 0: released as soon as the pipeline takes it (lossless).
//            agvslam-run adds laps, blacked-out frames, ground-truth masks and lossless paced play (DatasetPlayback).
//
// grab() never waits longer than its timeout, so the capture loop stays responsive to stop requests.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "agvslam/core/camera.h"
#include "agvslam/core/stereo_frame.h"
#include "agvslam/daemon/daemon_config.h"
#include "agvslam/io/dataset.h"

namespace agvslam::drivers::v4l2 {
class StereoCamera;
}

namespace agvslam::daemon {

// What prepare_source() found: the calibration of the rectified frames and the camera rate.
struct SourceSetup {
  std::shared_ptr<const io::StereoDataset> dataset;  // dataset source only
  StereoCalibration calibration;                     // of the frames the source delivers (rectified)
  double rate_hz = 0;                                // the camera's / dataset's own rate
  double slam_rate_hz = 0;                           // the rate the SLAM assumes (pipeline.frame_rate_hz or rate_hz)
  std::size_t first = 0, last = 0;                   // dataset: inclusive frame range
  std::string summary;                               // one line for the start-up echo
};

// The setup of a dataset source playing frames first..last (inclusive) of `dataset`; slam_rate_hz is the dataset's
// rate.
SourceSetup dataset_setup(std::shared_ptr<const io::StereoDataset> dataset, std::size_t first, std::size_t last);

// Opens the dataset index or loads the calibration file (no device is touched). Throws InputError naming the
// daemon's config file and the field (source.dataset, source.frames, calibration.file, pipeline.frame_rate_hz)
// for what cannot be read or does not fit (calibration size != camera.width x camera.height; no frame rate known).
SourceSetup prepare_source(const DaemonConfig& config);

struct CapturedFrame {
  StereoFrame frame;           // rectified; frame.index: pairs delivered by the source since start
  int64_t capture_t_ns = 0;    // CLOCK_REALTIME capture stamp (see above)
  int64_t source_index = -1;   // dataset: index of the frame in the dataset; V4L2: -1
  int64_t source_t_ns = 0;     // dataset: the frame's own time stamp; V4L2: CLOCK_MONOTONIC stamp of the left image
  int64_t queued_mono_ns = 0;  // CLOCK_MONOTONIC when the capture thread queued it (stage timing)
  // Dataset only:
  int lap = 0;                // DatasetPlayback::laps: which play of the range (frame.t_ns continues over laps)
  bool blank = false;         // DatasetPlayback::blank: the images were replaced by black ones
  cv::Mat ground_truth_mask;  // DatasetPlayback::ground_truth_masks: the dataset's moving-object mask (255)
  double read_ms = 0;         // decoding (and rectifying) the frame
};

struct SourceStats {
  uint64_t frames = 0;    // frames delivered
  uint64_t dropped = 0;   // frames the source itself lost (V4L2: sequence gaps, unpaired, corrupt; dataset: unreadable)
  bool connected = true;  // false while a camera is lost / being reopened
  uint64_t losses = 0;    // camera lost (error, stall, removal)
  uint64_t reopens = 0;   // and opened again
  std::string line;       // one line for the status / statistics log
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  enum class Grab { kFrame, kNoFrame, kEnd };
  // Waits at most timeout_ms. kEnd: a dataset played once has no more frames.
  virtual Grab grab(CapturedFrame& out, int timeout_ms) = 0;
  // True when frames are produced only as fast as they are taken (nothing may be dropped downstream).
  virtual bool lossless() const = 0;
  virtual SourceStats stats() const = 0;
  virtual std::string describe() const = 0;
};

// How a dataset is played besides its rate and range (agvslam-run's --repeat, --blank, --dynamic gt, --speed).
struct DatasetPlayback {
  // Play the range this many times in a row; the stamps of lap n are shifted by n * lap_duration_ns (laps of a
  // loop sequence that ends where it starts).
  int laps = 1;
  // Dataset indices first..last (inclusive) delivered as black images (a covered camera).
  std::optional<std::pair<std::size_t, std::size_t>> blank;
  bool ground_truth_masks = false;  // deliver the dataset's ground-truth mask with every frame
  // Paced play (rate > 0) whose frames must all be processed: the pipeline then waits instead of dropping.
  bool lossless = false;
};

// One lap of frames first..last: from the first stamp to the last plus one frame period (ns).
int64_t lap_duration_ns(const io::StereoDataset& dataset, std::size_t first, std::size_t last);

// Plays setup.dataset (see above).
class DatasetSource final : public FrameSource {
 public:
  DatasetSource(const SourceSetup& setup, const SourceConfig& config, const DatasetPlayback& playback = {});
  Grab grab(CapturedFrame& out, int timeout_ms) override;
  bool lossless() const override { return period_ns_ == 0 || playback_.lossless; }
  SourceStats stats() const override;
  std::string describe() const override;

 private:
  bool load_next();

  std::shared_ptr<const io::StereoDataset> dataset_;
  std::size_t first_, last_;
  bool loop_;
  DatasetPlayback playback_;
  int64_t lap_ns_;          // stamp shift per lap
  int64_t period_ns_;       // 0: as fast as taken
  std::size_t next_index_;  // dataset index of the frame to load next
  int lap_ = 0;
  bool have_pending_ = false, ended_ = false;
  CapturedFrame pending_;  // decoded, waiting for its due time
  int64_t start_mono_ns_ = -1;
  uint64_t delivered_ = 0;
  uint64_t skipped_ = 0;  // frames that could not be read (counted as dropped by the source)
};

// The V4L2 stereo camera.
class V4l2Source final : public FrameSource {
 public:
  // Opens the camera: with config.wait_for_camera a failure leaves it reopening with back-off; without, the
  // device's error is thrown (V4l2Error / InputError naming the device).
  V4l2Source(const SourceSetup& setup, const drivers::v4l2::V4l2CameraConfig& camera, bool wait_for_camera);
  ~V4l2Source() override;
  Grab grab(CapturedFrame& out, int timeout_ms) override;
  bool lossless() const override { return false; }
  SourceStats stats() const override;
  std::string describe() const override;

 private:
  StereoCalibration calibration_;
  std::unique_ptr<drivers::v4l2::StereoCamera> camera_;
  StereoFrame raw_;
};

std::unique_ptr<FrameSource> make_frame_source(const SourceSetup& setup, const DaemonConfig& config);

}  // namespace agvslam::daemon
