#include "agvslam/drivers/v4l2/pairing.h"

#include <cstring>
#include <stdexcept>

namespace agvslam::drivers::v4l2 {

uint32_t SequenceTracker::observe(uint32_t sequence) {
  uint32_t lost = 0;
  if (last_ && sequence > *last_) lost = sequence - *last_ - 1;
  dropped_ += lost;
  last_ = sequence;
  return lost;
}

TimestampPairer::TimestampPairer(int64_t tolerance_ns, std::size_t max_pending)
    : tolerance_ns_(tolerance_ns), max_pending_(max_pending < 1 ? 1 : max_pending) {}

void TimestampPairer::push(std::deque<EyeFrame>& q, const EyeFrame& f, uint64_t& unpaired, std::deque<int>& released) {
  if (!q.empty() && f.t_ns < q.back().t_ns) {  // out of order: the device went back in time; keep the queue sorted
    ++unpaired;
    released.push_back(f.slot);
    return;
  }
  q.push_back(f);
  while (q.size() > max_pending_) {
    ++unpaired;
    released.push_back(q.front().slot);
    q.pop_front();
  }
}

void TimestampPairer::push_left(const EyeFrame& f, std::deque<int>& released) {
  push(left_, f, unpaired_left_, released);
}
void TimestampPairer::push_right(const EyeFrame& f, std::deque<int>& released) {
  push(right_, f, unpaired_right_, released);
}

std::optional<PairedFrames> TimestampPairer::pop(std::deque<int>& released) {
  while (!left_.empty() && !right_.empty()) {
    const EyeFrame& l = left_.front();
    const EyeFrame& r = right_.front();
    const int64_t dt = l.t_ns - r.t_ns;
    if (dt <= tolerance_ns_ && dt >= -tolerance_ns_) {
      PairedFrames p{l, r};
      left_.pop_front();
      right_.pop_front();
      return p;
    }
    // The older of the two fronts can no longer find a partner: the other side's frames only get newer.
    if (dt < 0) {
      ++unpaired_left_;
      released.push_back(l.slot);
      left_.pop_front();
    } else {
      ++unpaired_right_;
      released.push_back(r.slot);
      right_.pop_front();
    }
  }
  return std::nullopt;
}

void TimestampPairer::clear(std::deque<int>& released) {
  for (const auto& f : left_) released.push_back(f.slot);
  for (const auto& f : right_) released.push_back(f.slot);
  left_.clear();
  right_.clear();
}

void split_side_by_side(const cv::Mat& sbs, cv::Mat& left, cv::Mat& right) {
  if (sbs.type() != CV_8UC1) throw std::invalid_argument("split_side_by_side: expected a CV_8UC1 image");
  if (sbs.cols % 2 != 0)
    throw std::invalid_argument("split_side_by_side: expected an even width, got " + std::to_string(sbs.cols));
  const int w = sbs.cols / 2;
  left.create(sbs.rows, w, CV_8UC1);
  right.create(sbs.rows, w, CV_8UC1);
  for (int y = 0; y < sbs.rows; ++y) {
    const uint8_t* row = sbs.ptr<uint8_t>(y);
    std::memcpy(left.ptr<uint8_t>(y), row, static_cast<std::size_t>(w));
    std::memcpy(right.ptr<uint8_t>(y), row + w, static_cast<std::size_t>(w));
  }
}

}  // namespace agvslam::drivers::v4l2
