#include "agvslam/daemon/frame_source.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <thread>

#include <spdlog/spdlog.h>

#include "agvslam/core/error.h"
#include "agvslam/drivers/v4l2/stereo_camera.h"
#include "agvslam/io/calibration_io.h"

namespace agvslam::daemon {
namespace {

using drivers::v4l2::monotonic_now_ns;
using drivers::v4l2::realtime_now_ns;

std::string rate_text(double hz) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f Hz", hz);
  return buf;
}

}  // namespace

SourceSetup dataset_setup(std::shared_ptr<const io::StereoDataset> dataset, std::size_t first, std::size_t last) {
  SourceSetup s;
  s.dataset = std::move(dataset);
  s.first = first;
  s.last = last;
  s.calibration = s.dataset->calibration();
  s.rate_hz = s.dataset->rate_hz();
  s.slam_rate_hz = s.rate_hz;
  s.summary = s.dataset->kind() + " dataset " + s.dataset->root() + ": " + std::to_string(s.dataset->size()) +
              " frames at " + rate_text(s.rate_hz) + ", playing " + std::to_string(s.first) + ".." +
              std::to_string(s.last) + "; calibration " + s.calibration.summary();
  return s;
}

SourceSetup prepare_source(const DaemonConfig& config) {
  SourceSetup s;
  if (config.source.type == SourceType::kDataset) {
    try {
      s.dataset = io::open_dataset(config.source.dataset, config.calibration_file);
    } catch (const InputError& e) {
      // The dataset reader names the file inside the folder; say which setting led there.
      const bool calib = !config.calibration_file.empty() && std::string(e.what()).find(config.calibration_file) == 0;
      throw InputError(
          config.path, calib ? "calibration.file" : "source.dataset",
          std::string(calib ? "expected a calibration file agvslam::io reads: "
                            : "expected a dataset folder (KITTI layout, agvslam-sim output, EuRoC ASL or rosbag2): ") +
              e.what());
    }
    std::size_t first = 0, last = 0;
    io::parse_frame_range(config.source.frames, s.dataset->size(), config.path, "source.frames", first, last);
    s = dataset_setup(s.dataset, first, last);
  } else {
    const cv::Size size(config.camera.width, config.camera.height);
    try {
      s.calibration = io::load_calibration(config.calibration_file, size);
    } catch (const InputError& e) {
      throw InputError(config.path, "calibration.file",
                       std::string("expected a calibration file agvslam::io reads: ") + e.what());
    }
    if (s.calibration.left.size() != size) {
      throw InputError(config.path, "calibration.file",
                       "expected a calibration of the camera's " + std::to_string(size.width) + "x" +
                           std::to_string(size.height) + " images (camera.width x camera.height), " +
                           config.calibration_file + " is for " + std::to_string(s.calibration.left.width) + "x" +
                           std::to_string(s.calibration.left.height));
    }
    s.rate_hz = config.camera.fps;
    s.summary = "V4L2 " + config.camera.describe() + "; calibration " + s.calibration.summary();
  }
  s.slam_rate_hz = config.pipeline.frame_rate_hz > 0 ? config.pipeline.frame_rate_hz : s.rate_hz;
  if (!(s.slam_rate_hz > 0)) {
    throw InputError(config.path, "pipeline.frame_rate_hz",
                     "expected the camera's frame rate in Hz (camera.fps is 0, so the SLAM cannot know it)");
  }
  return s;
}

// ---------------------------------------------------------------------------------------------------------------
// Dataset

int64_t lap_duration_ns(const io::StereoDataset& dataset, std::size_t first, std::size_t last) {
  const auto period_ns = static_cast<int64_t>(1e9 / dataset.rate_hz());
  return last > first ? dataset.timestamp_ns(last) - dataset.timestamp_ns(first) + period_ns : period_ns;
}

DatasetSource::DatasetSource(const SourceSetup& setup, const SourceConfig& config, const DatasetPlayback& playback)
    : dataset_(setup.dataset),
      first_(setup.first),
      last_(setup.last),
      loop_(config.loop),
      playback_(playback),
      lap_ns_(0),
      period_ns_(0),
      next_index_(setup.first) {
  if (!dataset_) throw std::logic_error("DatasetSource without a dataset");
  if (playback_.laps < 1) throw std::logic_error("DatasetSource: laps must be at least 1");
  if (playback_.laps > 1) lap_ns_ = lap_duration_ns(*dataset_, first_, last_);
  const double hz = config.rate_hz > 0 ? config.rate_hz : config.rate * setup.rate_hz;
  if (hz > 0) period_ns_ = static_cast<int64_t>(1e9 / hz + 0.5);
}

bool DatasetSource::load_next() {
  const auto t0 = std::chrono::steady_clock::now();
  // A frame whose image is unreadable (corrupt, truncated, empty, another size) is skipped, logged and counted:
  // one bad file must not end a run, as one corrupt camera frame does not. A range with no readable frame at all
  // is an error.
  for (std::size_t unreadable = 0;;) {
    if (next_index_ > last_) {
      if (lap_ + 1 < playback_.laps) {
        ++lap_;
      } else if (!loop_) {
        return false;
      }
      next_index_ = first_;
    }
    try {
      pending_.frame = dataset_->frame(next_index_);  // rectified, CV_8UC1
      break;
    } catch (const InputError& e) {
      if (++unreadable > last_ - first_) throw;
      ++skipped_;
      spdlog::warn("dataset: frame {} skipped ({} so far): {}", next_index_, skipped_, e.what());
      ++next_index_;
    }
  }
  pending_.frame.t_ns += lap_ * lap_ns_;
  pending_.blank = playback_.blank && next_index_ >= playback_.blank->first && next_index_ <= playback_.blank->second;
  if (pending_.blank) {
    pending_.frame.left = cv::Mat::zeros(pending_.frame.left.size(), pending_.frame.left.type());
    pending_.frame.right = cv::Mat::zeros(pending_.frame.right.size(), pending_.frame.right.type());
  }
  pending_.read_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  pending_.ground_truth_mask = playback_.ground_truth_masks ? dataset_->ground_truth_mask(next_index_) : cv::Mat();
  pending_.lap = lap_;
  pending_.source_index = static_cast<int64_t>(next_index_);
  pending_.source_t_ns = dataset_->timestamp_ns(next_index_);
  ++next_index_;
  have_pending_ = true;
  return true;
}

FrameSource::Grab DatasetSource::grab(CapturedFrame& out, int timeout_ms) {
  if (ended_) return Grab::kEnd;
  if (!have_pending_ && !load_next()) {
    ended_ = true;
    return Grab::kEnd;
  }
  if (period_ns_ > 0) {
    const int64_t now = monotonic_now_ns();
    if (start_mono_ns_ < 0) start_mono_ns_ = now;  // the first frame is due at once
    const int64_t due = start_mono_ns_ + static_cast<int64_t>(delivered_) * period_ns_;
    if (now < due) {
      const int64_t wait = std::min<int64_t>(due - now, static_cast<int64_t>(timeout_ms) * 1000000LL);
      std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
      if (monotonic_now_ns() < due) return Grab::kNoFrame;
    }
  }
  out = std::move(pending_);
  have_pending_ = false;
  out.frame.index = delivered_;
  out.capture_t_ns = realtime_now_ns();  // the camera "delivers" the frame now
  ++delivered_;
  return Grab::kFrame;
}

SourceStats DatasetSource::stats() const {
  SourceStats s;
  s.frames = delivered_;
  s.dropped = skipped_;
  s.connected = true;
  s.line = "dataset: " + std::to_string(delivered_) + " frames played" +
           (skipped_ > 0 ? ", " + std::to_string(skipped_) + " unreadable skipped" : "") + (ended_ ? ", ended" : "");
  return s;
}

std::string DatasetSource::describe() const {
  return "dataset " + dataset_->root() + " frames " + std::to_string(first_) + ".." + std::to_string(last_) + ", " +
         (period_ns_ > 0 ? rate_text(1e9 / static_cast<double>(period_ns_)) : std::string("as fast as taken")) +
         (playback_.laps > 1 ? ", " + std::to_string(playback_.laps) + " laps" : std::string()) +
         (loop_ ? ", looped" : ", once");
}

// ---------------------------------------------------------------------------------------------------------------
// V4L2

V4l2Source::V4l2Source(const SourceSetup& setup, const drivers::v4l2::V4l2CameraConfig& camera, bool wait_for_camera)
    : calibration_(setup.calibration), camera_(std::make_unique<drivers::v4l2::StereoCamera>(camera)) {
  camera_->open(/*throw_on_failure=*/!wait_for_camera);
}

V4l2Source::~V4l2Source() {
  if (camera_) camera_->close();
}

FrameSource::Grab V4l2Source::grab(CapturedFrame& out, int timeout_ms) {
  drivers::v4l2::CaptureInfo info;
  if (camera_->grab(raw_, timeout_ms, &info) != drivers::v4l2::StereoCamera::Grab::kFrame) return Grab::kNoFrame;
  out.frame.index = raw_.index;
  out.frame.t_ns = raw_.t_ns;
  if (calibration_.needs_rectification) {
    // New buffers: the frame travels through the queues while the next one is rectified.
    cv::Mat left, right;
    calibration_.rectify(raw_.left, raw_.right, left, right);
    out.frame.left = left;
    out.frame.right = right;
    raw_.left.release();
    raw_.right.release();
  } else {
    out.frame.left = std::move(raw_.left);  // the camera reuses its buffer once the pipeline releases it
    out.frame.right = std::move(raw_.right);
    raw_.left = cv::Mat();
    raw_.right = cv::Mat();
  }
  out.capture_t_ns = raw_.t_ns + info.realtime_minus_monotonic_ns;
  out.source_index = -1;
  out.source_t_ns = raw_.t_ns;
  return Grab::kFrame;
}

SourceStats V4l2Source::stats() const {
  const drivers::v4l2::CaptureStats& c = camera_->stats();
  SourceStats s;
  s.frames = c.frames;
  // A frame lost on one eye leaves its partner unpaired: count pairs, not images.
  s.dropped = std::max(c.dropped_left + c.unpaired_left, c.dropped_right + c.unpaired_right) + c.corrupt;
  s.connected = c.state == drivers::v4l2::CaptureStats::State::kStreaming;
  s.losses = c.device_losses;
  s.reopens = c.reopens;
  s.line = camera_->stats_line();
  return s;
}

std::string V4l2Source::describe() const { return "V4L2 " + camera_->config().describe(); }

std::unique_ptr<FrameSource> make_frame_source(const SourceSetup& setup, const DaemonConfig& config) {
  if (config.source.type == SourceType::kDataset) return std::make_unique<DatasetSource>(setup, config.source);
  return std::make_unique<V4l2Source>(setup, config.camera, config.source.wait_for_camera);
}

}  // namespace agvslam::daemon
