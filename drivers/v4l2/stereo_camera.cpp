#include "agvslam/drivers/v4l2/stereo_camera.h"

#include <poll.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>
#include <ctime>
#include <sstream>
#include <thread>

#include <spdlog/spdlog.h>

#include "agvslam/drivers/v4l2/device.h"

namespace agvslam::drivers::v4l2 {

int64_t monotonic_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

int64_t realtime_now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

const char* to_string(CaptureStats::State s) {
  switch (s) {
    case CaptureStats::State::kClosed:
      return "closed";
    case CaptureStats::State::kStreaming:
      return "streaming";
    case CaptureStats::State::kReopening:
      return "reopening";
  }
  return "?";
}

struct StereoCamera::Eye {
  std::string path;
  std::unique_ptr<V4l2Device> device;
  SequenceTracker sequence;
  int64_t last_frame_ns = 0;
};

StereoCamera::StereoCamera(V4l2CameraConfig config)
    : config_(std::move(config)),
      pairer_(static_cast<int64_t>(config_.pair_tolerance_ms * 1e6), static_cast<std::size_t>(config_.max_pending)) {
  config_.validate("camera configuration");
  for (const auto& path : config_.devices()) {
    auto e = std::make_unique<Eye>();
    e->path = path;
    eyes_.push_back(std::move(e));
  }
  // Per side: max_pending queued, one being filled, one or two held by the caller.
  const std::size_t per_side = static_cast<std::size_t>(config_.max_pending) + 3;
  left_pool_.resize(per_side);
  right_pool_.resize(per_side);
  left_busy_.assign(per_side, false);
  right_busy_.assign(per_side, false);
  backoff_ms_ = config_.reopen_backoff_initial_ms;
}

StereoCamera::~StereoCamera() = default;

void StereoCamera::open_devices() {
  CaptureRequest r;
  r.width = config_.device_width();
  r.height = config_.height;
  r.pixel_format = config_.pixel_format;
  r.fps = config_.fps;
  r.buffers = config_.buffers;
  for (auto& e : eyes_) e->device.reset();
  try {
    for (auto& e : eyes_) {
      e->device = std::make_unique<V4l2Device>(e->path, r);
      e->sequence.reset();
      e->last_frame_ns = monotonic_now_ns();
    }
  } catch (...) {
    for (auto& e : eyes_) e->device.reset();
    throw;
  }
  for (auto& e : eyes_)
    spdlog::info("camera: {} streaming ('{}', {} frames/s reported, time stamps {})", e->path, e->device->card(),
                 e->device->actual_fps(), e->device->timestamp_source());
  stats_.state = CaptureStats::State::kStreaming;
}

void StereoCamera::open(bool throw_on_failure) {
  try {
    open_devices();
    ever_opened_ = true;
    backoff_ms_ = config_.reopen_backoff_initial_ms;
  } catch (const V4l2Error& e) {
    stats_.last_error = e.what();
    if (throw_on_failure) throw;
    spdlog::warn("camera: {}; retrying with back-off", e.what());
    stats_.state = CaptureStats::State::kReopening;
    next_reopen_ns_ = monotonic_now_ns() + static_cast<int64_t>(backoff_ms_) * 1000000LL;
  }
}

void StereoCamera::close() {
  for (auto& e : eyes_) e->device.reset();
  pairer_.clear(released_);
  released_.clear();
  std::fill(left_busy_.begin(), left_busy_.end(), false);
  std::fill(right_busy_.begin(), right_busy_.end(), false);
  stats_.state = CaptureStats::State::kClosed;
}

void StereoCamera::lose(const std::string& why) {
  if (stats_.state == CaptureStats::State::kStreaming) ++stats_.device_losses;
  stats_.last_error = why;
  spdlog::warn("camera: lost: {}; reopening with back-off from {} ms", why, config_.reopen_backoff_initial_ms);
  close();
  stats_.state = CaptureStats::State::kReopening;
  backoff_ms_ = config_.reopen_backoff_initial_ms;
  next_reopen_ns_ = monotonic_now_ns() + static_cast<int64_t>(backoff_ms_) * 1000000LL;
}

bool StereoCamera::try_reopen() {
  try {
    open_devices();
  } catch (const V4l2Error& e) {
    ++stats_.reopen_attempts;
    if (stats_.last_error != e.what() || stats_.reopen_attempts % 10 == 0)
      spdlog::warn("camera: reopen attempt {} failed: {}; next in {} ms", stats_.reopen_attempts, e.what(),
                   backoff_ms_);
    stats_.last_error = e.what();
    next_reopen_ns_ = monotonic_now_ns() + static_cast<int64_t>(backoff_ms_) * 1000000LL;
    backoff_ms_ = std::min(2 * backoff_ms_, config_.reopen_backoff_max_ms);
    return false;
  }
  if (ever_opened_) {
    ++stats_.reopens;
    spdlog::info("camera: reopened after {} failed attempts", stats_.reopen_attempts);
  }
  ever_opened_ = true;
  backoff_ms_ = config_.reopen_backoff_initial_ms;
  return true;
}

// Slots are ids into one of the pools: left ids 0..n-1, right ids n..2n-1. A slot whose image the caller still
// holds (reference count > 1) is only used when nothing else is free, and then gets a new buffer.
int StereoCamera::free_slot(int eye) {
  auto& pool = eye == 0 ? left_pool_ : right_pool_;
  auto& busy = eye == 0 ? left_busy_ : right_busy_;
  const int base = eye == 0 ? 0 : static_cast<int>(left_pool_.size());
  for (std::size_t i = 0; i < pool.size(); ++i)
    if (!busy[i] && (pool[i].u == nullptr || pool[i].u->refcount <= 1)) return base + static_cast<int>(i);
  for (std::size_t i = 0; i < pool.size(); ++i)
    if (!busy[i]) {
      pool[i] = cv::Mat();
      return base + static_cast<int>(i);
    }
  // Cannot happen: at most max_pending frames queue per side.
  pool[0] = cv::Mat();
  busy[0] = false;
  return base;
}

bool StereoCamera::read_eye(int eye, std::deque<int>& released) {
  Eye& e = *eyes_[static_cast<std::size_t>(eye)];
  CapturedImage ci;
  const bool sbs = config_.side_by_side;
  int slot = -1;
  cv::Mat* target = &sbs_grey_;
  if (!sbs) {
    slot = free_slot(eye);
    target = eye == 0 ? &left_pool_[static_cast<std::size_t>(slot)]
                      : &right_pool_[static_cast<std::size_t>(slot) - left_pool_.size()];
  }
  if (!e.device->dequeue(*target, ci)) return false;
  e.last_frame_ns = monotonic_now_ns();
  const uint32_t lost = e.sequence.observe(ci.sequence);
  (eye == 0 ? stats_.dropped_left : stats_.dropped_right) += lost;
  if (ci.error_flag) {
    ++stats_.corrupt;
    return true;
  }
  if (sbs) {
    const int l = free_slot(0), r = free_slot(1);
    split_side_by_side(sbs_grey_, left_pool_[static_cast<std::size_t>(l)],
                       right_pool_[static_cast<std::size_t>(r) - left_pool_.size()]);
    left_busy_[static_cast<std::size_t>(l)] = true;
    right_busy_[static_cast<std::size_t>(r) - left_pool_.size()] = true;
    pairer_.push_left({ci.t_ns, ci.sequence, l}, released);
    pairer_.push_right({ci.t_ns, ci.sequence, r}, released);
  } else if (eye == 0) {
    left_busy_[static_cast<std::size_t>(slot)] = true;
    pairer_.push_left({ci.t_ns, ci.sequence, slot}, released);
  } else {
    right_busy_[static_cast<std::size_t>(slot) - left_pool_.size()] = true;
    pairer_.push_right({ci.t_ns, ci.sequence, slot}, released);
  }
  return true;
}

StereoCamera::Grab StereoCamera::grab(StereoFrame& frame, int timeout_ms, CaptureInfo* info) {
  const int64_t deadline = monotonic_now_ns() + static_cast<int64_t>(std::max(timeout_ms, 0)) * 1000000LL;
  auto release_slots = [&] {
    for (int s : released_) {
      if (s < 0) continue;
      const auto i = static_cast<std::size_t>(s);
      if (i < left_pool_.size())
        left_busy_[i] = false;
      else
        right_busy_[i - left_pool_.size()] = false;
    }
    released_.clear();
  };
  for (;;) {
    int64_t now = monotonic_now_ns();
    if (stats_.state != CaptureStats::State::kStreaming) {
      if (now >= next_reopen_ns_) {
        if (try_reopen()) continue;
        now = monotonic_now_ns();
      }
      if (now >= deadline) return Grab::kNoFrame;
      const int64_t wait = std::min(next_reopen_ns_, deadline) - now;
      if (wait > 0) std::this_thread::sleep_for(std::chrono::nanoseconds(wait));
      continue;
    }

    // A pair may already be waiting.
    if (auto p = pairer_.pop(released_)) {
      release_slots();
      const auto li = static_cast<std::size_t>(p->left.slot);
      const auto ri = static_cast<std::size_t>(p->right.slot) - left_pool_.size();
      left_busy_[li] = false;
      right_busy_[ri] = false;
      frame.index = static_cast<std::size_t>(stats_.frames++);
      frame.t_ns = p->left.t_ns;
      frame.left = left_pool_[li];
      frame.right = right_pool_[ri];
      stats_.unpaired_left = pairer_.unpaired_left();
      stats_.unpaired_right = pairer_.unpaired_right();
      if (info) {
        info->t_left_ns = p->left.t_ns;
        info->t_right_ns = p->right.t_ns;
        info->sequence_left = p->left.sequence;
        info->sequence_right = p->right.sequence;
        info->dequeued_ns = monotonic_now_ns();
        info->realtime_minus_monotonic_ns = realtime_now_ns() - info->dequeued_ns;
      }
      return Grab::kFrame;
    }
    release_slots();
    stats_.unpaired_left = pairer_.unpaired_left();
    stats_.unpaired_right = pairer_.unpaired_right();

    // Stalled device?
    const int64_t stall_ns = static_cast<int64_t>(config_.stall_timeout_ms) * 1000000LL;
    int64_t next_stall = INT64_MAX;
    bool stalled = false;
    for (auto& e : eyes_) {
      if (now - e->last_frame_ns > stall_ns) {
        lose(e->path + ": no frame for " + std::to_string((now - e->last_frame_ns) / 1000000) +
             " ms (stall_timeout_ms " + std::to_string(config_.stall_timeout_ms) + ")");
        stalled = true;
        break;
      }
      next_stall = std::min(next_stall, e->last_frame_ns + stall_ns);
    }
    if (stalled) continue;
    if (now >= deadline) return Grab::kNoFrame;

    const int64_t until = std::min(deadline, next_stall);
    const int wait_ms = static_cast<int>(std::max<int64_t>(1, (until - now + 999999) / 1000000));
    pollfd fds[2]{};
    const std::size_t n = eyes_.size();
    for (std::size_t i = 0; i < n; ++i) fds[i] = {eyes_[i]->device->fd(), POLLIN | POLLPRI, 0};
    const int r = ::poll(fds, static_cast<nfds_t>(n), wait_ms);
    if (r < 0) {
      if (errno == EINTR) continue;
      lose(std::string("poll failed: ") + std::strerror(errno));
      continue;
    }
    try {
      for (std::size_t i = 0; i < n; ++i) {
        if (fds[i].revents & POLLNVAL) throw V4l2Error(eyes_[i]->path, "poll: fd no longer valid");
        // POLLERR: not streaming any more, or the device is gone; DQBUF says which.
        if (fds[i].revents & (POLLIN | POLLERR | POLLHUP)) {
          while (read_eye(static_cast<int>(i), released_)) {
          }
        }
      }
    } catch (const V4l2Error& e) {
      lose(e.what());
    }
  }
}

std::string StereoCamera::stats_line() const {
  std::ostringstream s;
  s << "camera " << to_string(stats_.state) << ": frames " << stats_.frames << ", dropped " << stats_.dropped_left
    << "/" << stats_.dropped_right << ", unpaired " << stats_.unpaired_left << "/" << stats_.unpaired_right
    << ", corrupt " << stats_.corrupt << ", losses " << stats_.device_losses << ", reopens " << stats_.reopens
    << " (failed attempts " << stats_.reopen_attempts << ")";
  if (!stats_.last_error.empty()) s << ", last error: " << stats_.last_error;
  return s.str();
}

}  // namespace agvslam::drivers::v4l2
