#include "agvslam/drivers/can/can_publisher.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstring>

namespace agvslam::drivers::can {

CanPosePublisher::CanPosePublisher(const CanConfig& config, std::vector<CanId> receive)
    : config_(config), receive_(std::move(receive)), backoff_(std::chrono::milliseconds(config.reopen_min_ms)) {
  config_.validate("CanConfig");
  try_open(Clock::now());
}

bool CanPosePublisher::try_open(Clock::time_point now) {
  ++stats_.reopen_attempts;
  std::string error;
  if (socket_.open(config_.interface, config_.fd, &error, receive_)) {
    if (stats_.reopens > 0) spdlog::info("can: {} reopened after '{}'", config_.interface, last_error_);
    ++stats_.reopens;
    backoff_ = std::chrono::milliseconds(config_.reopen_min_ms);
    return true;
  }
  if (error != last_error_)
    spdlog::warn("can: {} (retrying every {}..{} ms)", error, config_.reopen_min_ms, config_.reopen_max_ms);
  last_error_ = error;
  next_reopen_ = now + backoff_;
  backoff_ = std::min(backoff_ * 2, std::chrono::milliseconds(config_.reopen_max_ms));
  return false;
}

void CanPosePublisher::mark_down(Clock::time_point now, const std::string& why) {
  socket_.close();
  if (why != last_error_) spdlog::warn("can: {}: {}; reopening with back-off", config_.interface, why);
  last_error_ = why;
  backoff_ = std::chrono::milliseconds(config_.reopen_min_ms);
  next_reopen_ = now + backoff_;
}

CanPublishResult CanPosePublisher::publish(const PoseSample& sample) {
  CanPublishResult result;
  ++stats_.poses_submitted;
  // Rate: a schedule in capture time; a pose is due when it reaches the next slot (10 % early is fine).
  if (config_.rate_hz > 0.0) {
    const auto period_ns = static_cast<int64_t>(1e9 / config_.rate_hz);
    if (next_due_t_ns_ != INT64_MIN && sample.t_ns + period_ns / 10 < next_due_t_ns_) return result;
    next_due_t_ns_ = (next_due_t_ns_ == INT64_MIN || sample.t_ns - next_due_t_ns_ > period_ns)
                         ? sample.t_ns + period_ns
                         : next_due_t_ns_ + period_ns;
  }
  result.due = true;
  ++stats_.cycles;
  const uint64_t cycle = cycle_index_++;
  result.counter = counter_;
  counter_ = static_cast<uint8_t>((counter_ + 1) & 0xFU);

  std::size_t n = 0;
  const bool with_status = cycle % static_cast<uint64_t>(config_.status_every) == 0;
  if (config_.fd) {
    frames_[0] = encode_fd_frame(sample, result.counter, config_.layout());
    n = 1;
  } else {
    std::array<CanFrameBytes, kMaxClassicFrames> classic;
    n = encode_classic_frames(sample, result.counter, config_.layout(), config_.send_velocity, config_.send_stddev,
                              with_status, classic);
    std::copy(classic.begin(), classic.begin() + static_cast<std::ptrdiff_t>(n), frames_.begin());
  }
  if (with_status && sample.odometry_check.state != OdometryCheckState::kOff) {
    frames_[n++] = encode_odometry_check_frame(sample.odometry_check, result.counter, config_.layout());
  }

  const Clock::time_point now = Clock::now();
  read_pending(now);
  if (!socket_.is_open()) {
    stats_.frames_dropped_down += n;
    return result;
  }
  for (std::size_t i = 0; i < n; ++i) {
    int err = 0;
    switch (socket_.send(frames_[i], &err)) {
      case SendResult::kSent:
        ++stats_.frames_sent;
        ++result.frames_sent;
        break;
      case SendResult::kNoBuffer:  // queue full: drop the rest of this cycle, the next pose supersedes it
        stats_.frames_dropped_no_buffer += n - i;
        return result;
      case SendResult::kDown:
        stats_.frames_dropped_down += n - i;
        mark_down(now, std::string("send: ") + std::strerror(err));
        return result;
      case SendResult::kError:
        ++stats_.frames_failed;
        if (err != last_errno_logged_) spdlog::warn("can: {}: send: {}", config_.interface, std::strerror(err));
        last_errno_logged_ = err;
        break;
    }
  }
  result.sent = result.frames_sent == static_cast<int>(n);
  if (result.sent) ++stats_.cycles_sent;
  return result;
}

void CanPosePublisher::read_pending(Clock::time_point now) {
  if (!socket_.is_open() && now >= next_reopen_) try_open(now);
  if (!socket_.is_open()) return;
  const std::size_t before = received_.size();
  const bool bus_off = socket_.drain(stats_.error_frames, receive_.empty() ? nullptr : &received_);
  stats_.frames_received += received_.size() - before;
  if (received_.size() > kMaxReceivedPending) {
    const std::size_t excess = received_.size() - kMaxReceivedPending;
    received_.erase(received_.begin(), received_.begin() + static_cast<std::ptrdiff_t>(excess));
    stats_.frames_received_dropped += excess;
  }
  if (bus_off) mark_down(now, "controller reported bus-off");
}

void CanPosePublisher::poll() { read_pending(Clock::now()); }

std::vector<ReceivedCanFrame> CanPosePublisher::take_received() {
  std::vector<ReceivedCanFrame> out;
  out.swap(received_);
  return out;
}

CanPublisherStats CanPosePublisher::stats() const {
  CanPublisherStats s = stats_;
  s.open = socket_.is_open();
  return s;
}

}  // namespace agvslam::drivers::can
