#pragma once
// The semantic stage beside tracking: per frame, in the thread that runs the geometric detector (in agvslamd and
// agvslam-run the detector thread, one frame ahead of tracking), process()
//   1. carries the objects of the previous frame into this one by LK (mask_propagation.h);
//   2. asks the worker to segment this frame when KeyframeSelector says so (paper 002);
//   3. takes a finished segmentation from the worker: the current frame's is used as it is, an earlier frame's
//      (late) is carried from the image it was computed on through every frame since to this one by LK (one step
//      per frame: a walking person's legs defeat one long step), one older than
//      propagation.max_late_frames is dropped (never applied to a frame it does not belong to); the worker has
//      already cut it into objects, seeded their corners and built that image's pyramid; its objects continue
//      the carried ones they overlap (their motion evidence with them);
//   4. decides per object whether it moves (object_motion.h, paper 001) from the geometric detector's points;
//   5. fuses the moving objects' masks with the detector's mask (fusion.mode).
// The network runs in the worker's own thread behind a one-slot queue in which the newest request wins, so a slow
// segmentation never stalls that thread or tracking (fusion.synchronous waits for each one instead: offline
// evaluation).

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <opencv2/core.hpp>
#include <thread>
#include <utility>
#include <vector>

#include "agvslam/core/bounded_queue.h"
#include "agvslam/dynamic/detection_result.h"
#include "agvslam/semantic/keyframe_selector.h"
#include "agvslam/semantic/mask_propagation.h"
#include "agvslam/semantic/object_motion.h"
#include "agvslam/semantic/segmenter.h"
#include "agvslam/semantic/semantic_config.h"

namespace agvslam::semantic {

struct SemanticFrame {
  std::size_t frame_index = 0;
  SegmentReason requested = SegmentReason::kNone;  // why this frame was sent to the network (kNone: not sent)
  int result_age_frames = -1;  // a segmentation arrived this frame, computed this many frames ago (-1: none)
  std::vector<SemanticObject> objects;
  std::vector<MotionVote> votes;  // per object, this frame
  cv::Mat moving_mask;            // CV_8UC1, 255 = a moving segmented object (dilated)
  cv::Mat fused_mask;             // CV_8UC1, 255 = dynamic after fusion with the detector's mask
  double process_ms = 0;          // what process() cost its caller's thread
};

struct SemanticStats {
  uint64_t requests = 0;          // frames sent to the worker
  uint64_t segmented = 0;         // segmentations that arrived
  uint64_t dropped_requests = 0;  // replaced in the queue by a newer one before the worker took them
  uint64_t late_results = 0;      // arrived for an earlier frame and were carried to the current one
  uint64_t stale_results = 0;     // older than max_late_frames: dropped
  double segment_ms_total = 0;    // worker time in the network
};

class SemanticMasker {
 public:
  // Class ids per pixel (CV_8UC1, the image's size) of a CV_8UC1 image; runs in the worker thread.
  using SegmentFunction = std::function<cv::Mat(const cv::Mat& grey)>;

  // Starts the worker around a loaded segmenter (so a bad model is an InputError before anything runs).
  SemanticMasker(const SemanticConfig& config, std::unique_ptr<Segmenter> segmenter);
  // The same around any segmentation function (tests: ground truth with a chosen delay).
  SemanticMasker(const SemanticConfig& config, SegmentFunction segment);
  ~SemanticMasker();
  SemanticMasker(const SemanticMasker&) = delete;
  SemanticMasker& operator=(const SemanticMasker&) = delete;

  // One frame (CV_8UC1 left image) after the detector ran on it; `geometry` may be null (no detector: the motion
  // test then has no points, and fusion uses the semantic masks alone). Frame indices must increase.
  const SemanticFrame& process(std::size_t frame_index, const cv::Mat& grey, const dynamic::DetectorResult* geometry,
                               const FrameCues& cues);

  // Writes the last process()'s fusion into the detector's mask (what the tools score, write and hand to tracking):
  // the image becomes fused_mask; with union the detector's instances stay and each moving segmented object adds
  // its pixels not yet covered to the detector's instance it overlaps most (the same object found by both), or as
  // an instance of its own (ids after the detector's, at most 255); with semantic the instances are the moving
  // objects alone; with geometry nothing changes. Regions grow with the pixels added to them.
  void apply_fusion(dynamic::DynamicMask& mask) const;

  // Forgets the objects and starts again as at the first frame (after a reset of tracking).
  void reset();

  SemanticStats stats() const;
  const SemanticConfig& config() const { return config_; }

 private:
  struct Request {
    std::size_t frame_index;
    cv::Mat grey;
  };
  // The worker's answer: the objects of the segmented frame with their corners, and that image's pyramid, so the
  // caller's thread only has to carry them.
  struct Result {
    std::size_t frame_index;
    std::vector<SemanticObject> objects;
    std::vector<cv::Mat> pyramid;
    double ms;  // in the network
  };

  void work();
  // Adopts a segmentation of frame `result.frame_index` into the current frame's objects.
  void adopt(const Result& result);

  SemanticConfig config_;
  std::vector<int> movable_ids_;
  SegmentFunction segment_;
  KeyframeSelector selector_;
  ObjectMotionTest motion_;

  BoundedQueue<Request> requests_;
  BoundedQueue<Result> results_;
  std::thread worker_;

  // State of the caller's thread.
  SemanticFrame frame_;
  // The pyramids of the last max_late_frames + 1 frames, the current one last, for carrying late results.
  std::deque<std::pair<std::size_t, std::vector<cv::Mat>>> pyramids_;
  int next_object_id_ = 1;
  bool has_previous_ = false;
  SemanticStats stats_;
};

}  // namespace agvslam::semantic
