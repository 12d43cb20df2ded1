#pragma once
// Pure logic of the stereo capture (no device I/O), so it is tested on synthetic input:
//   SequenceTracker   counts frames a device dropped, from the gaps in V4L2 buffer sequence numbers
//   TimestampPairer   pairs left and right frames whose time stamps differ by at most a tolerance; frames left
//                     without a partner are dropped and counted
//   split_side_by_side  one (2W x H) image into left and right (W x H) images

#include <cstddef>
#include <cstdint>
#include <deque>
#include <optional>

#include <opencv2/core.hpp>

namespace agvslam::drivers::v4l2 {

class SequenceTracker {
 public:
  // Records a buffer's sequence number; returns how many frames were lost just before it (0 when in order).
  // A sequence number that does not advance (a device restart, a driver that counts from 0 again) resets the
  // tracker without counting.
  uint32_t observe(uint32_t sequence);
  void reset() { last_.reset(); }
  uint64_t dropped() const { return dropped_; }

 private:
  std::optional<uint32_t> last_;
  uint64_t dropped_ = 0;
};

// One captured frame of one eye, as the pairer sees it: its time stamp and an opaque slot id (where the caller
// keeps the image).
struct EyeFrame {
  int64_t t_ns = 0;
  uint32_t sequence = 0;
  int slot = -1;
};

struct PairedFrames {
  EyeFrame left, right;
};

class TimestampPairer {
 public:
  TimestampPairer(int64_t tolerance_ns, std::size_t max_pending);

  // Queue a frame; a side holding more than max_pending frames drops its oldest (counted as unpaired).
  // Frames must arrive per side in increasing time order (a frame older than its side's newest is dropped).
  // The slots of dropped frames are appended to `released` (so the caller can reuse them); slot ids are the
  // caller's and must tell left from right if it shares one pool.
  void push_left(const EyeFrame& f, std::deque<int>& released);
  void push_right(const EyeFrame& f, std::deque<int>& released);

  // The next pair when one is ready. Frames with no partner within the tolerance (the other side has a newer
  // frame, so none can come) are dropped, counted and their slots appended to `released`.
  std::optional<PairedFrames> pop(std::deque<int>& released);

  void clear(std::deque<int>& released);
  std::size_t pending_left() const { return left_.size(); }
  std::size_t pending_right() const { return right_.size(); }
  uint64_t unpaired_left() const { return unpaired_left_; }
  uint64_t unpaired_right() const { return unpaired_right_; }
  int64_t tolerance_ns() const { return tolerance_ns_; }

 private:
  void push(std::deque<EyeFrame>& q, const EyeFrame& f, uint64_t& unpaired, std::deque<int>& released);
  int64_t tolerance_ns_;
  std::size_t max_pending_;
  std::deque<EyeFrame> left_, right_;
  uint64_t unpaired_left_ = 0, unpaired_right_ = 0;
};

// Copies the left and right halves of a (2W x H) CV_8UC1 image into left and right (W x H, continuous), reusing
// their buffers when they already have that size. Throws std::invalid_argument for an odd width or a non-grey
// image.
void split_side_by_side(const cv::Mat& sbs, cv::Mat& left, cv::Mat& right);

}  // namespace agvslam::drivers::v4l2
