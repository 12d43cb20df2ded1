#include "agvslam/semantic/semantic_masker.h"

#include <algorithm>
#include <chrono>
#include <opencv2/imgproc.hpp>

#include "agvslam/core/clock.h"

namespace agvslam::semantic {

SemanticMasker::SemanticMasker(const SemanticConfig& config, std::unique_ptr<Segmenter> segmenter)
    : SemanticMasker(config, [net = std::shared_ptr<Segmenter>(std::move(segmenter))](const cv::Mat& grey) {
        return net->segment(grey);
      }) {}

SemanticMasker::SemanticMasker(const SemanticConfig& config, SegmentFunction segment)
    : config_(config),
      movable_ids_(config.model.movable_ids()),
      segment_(std::move(segment)),
      selector_(config.keyframes),
      motion_(config.motion),
      // One pending request: a newer frame replaces one the worker has not started, the newest image matters.
      requests_(1, QueuePolicy::kNewestWins),
      results_(4, QueuePolicy::kNewestWins) {
  config_.validate("semantic settings");
  worker_ = std::thread([this] { work(); });
}

SemanticMasker::~SemanticMasker() {
  requests_.close();
  if (worker_.joinable()) worker_.join();
}

void SemanticMasker::work() {
  while (true) {
    std::optional<Request> request = requests_.pop_unless([] { return false; });
    if (!request) return;  // closed and empty
    const auto t0 = std::chrono::steady_clock::now();
    const cv::Mat labels = segment_(request->grey);
    Result result{request->frame_index, {}, {}, ms_since(t0)};
    result.objects = extract_objects(labels, movable_ids_, config_.propagation.min_object_pixels);
    seed_corners(request->grey, config_.propagation, result.objects);
    result.pyramid = lk_pyramid(request->grey, config_.propagation);
    results_.push(std::move(result));
  }
}

void SemanticMasker::reset() {
  selector_.reset();
  frame_.objects.clear();
  pyramids_.clear();
  has_previous_ = false;
}

SemanticStats SemanticMasker::stats() const {
  SemanticStats s = stats_;
  s.dropped_requests = requests_.dropped();
  return s;
}

void SemanticMasker::adopt(const Result& result) {
  const std::size_t age = frame_.frame_index - result.frame_index;
  // The frames processed after the segmented one, each with its pyramid (kept for max_late_frames frames).
  auto next =
      std::find_if(pyramids_.begin(), pyramids_.end(), [&](const auto& p) { return p.first > result.frame_index; });
  if (result.frame_index > frame_.frame_index || age > static_cast<std::size_t>(config_.propagation.max_late_frames) ||
      (age > 0 && next == pyramids_.end())) {
    ++stats_.stale_results;
    return;
  }
  std::vector<SemanticObject> found = result.objects;
  if (age > 0) {
    ++stats_.late_results;
    const std::vector<cv::Mat>* from = &result.pyramid;
    for (; next != pyramids_.end(); ++next) {
      carry_objects(*from, next->second, config_.propagation, found);
      from = &next->second;
    }
  }
  // Each new object continues the carried object of its class it overlaps most (its motion evidence with it).
  std::vector<bool> continued(frame_.objects.size(), false);
  for (SemanticObject& object : found) {
    double best_iou = config_.propagation.min_match_iou;
    int best = -1;
    for (std::size_t i = 0; i < frame_.objects.size(); ++i) {
      if (continued[i] || frame_.objects[i].class_id != object.class_id) continue;
      const double iou = mask_iou(object.mask, frame_.objects[i].mask);
      if (iou >= best_iou) {
        best_iou = iou;
        best = static_cast<int>(i);
      }
    }
    if (best >= 0) {
      const SemanticObject& old = frame_.objects[static_cast<std::size_t>(best)];
      continued[static_cast<std::size_t>(best)] = true;
      object.id = old.id;
      object.frames_seen = old.frames_seen;
      object.evidence = old.evidence;
      object.moving = old.moving;
      object.flow_px = old.flow_px;
      object.flow_known = old.flow_known;
    } else {
      object.id = next_object_id_++;
    }
  }
  frame_.objects = std::move(found);
  frame_.result_age_frames = static_cast<int>(age);
  ++stats_.segmented;
  stats_.segment_ms_total += result.ms;
}

const SemanticFrame& SemanticMasker::process(std::size_t frame_index, const cv::Mat& grey,
                                             const dynamic::DetectorResult* geometry, const FrameCues& cues) {
  const auto t0 = std::chrono::steady_clock::now();
  CV_Assert(grey.type() == CV_8UC1);
  frame_.frame_index = frame_index;
  frame_.requested = SegmentReason::kNone;
  frame_.result_age_frames = -1;
  frame_.votes.clear();
  const bool has_previous = has_previous_ && !pyramids_.empty();
  pyramids_.emplace_back(frame_index, lk_pyramid(grey, config_.propagation));
  while (pyramids_.size() > static_cast<std::size_t>(config_.propagation.max_late_frames) + 1) pyramids_.pop_front();
  const std::vector<cv::Mat>& pyramid = pyramids_.back().second;

  // 1. The previous frame's objects into this one (before a result replaces them, so matching sees them here).
  if (has_previous && pyramids_.size() >= 2 && !frame_.objects.empty()) {
    carry_objects(pyramids_[pyramids_.size() - 2].second, pyramid, config_.propagation, frame_.objects);
  } else {
    for (SemanticObject& object : frame_.objects) object.flow_known = false;
  }
  // Objects whose corners ran out get new ones where they now are.
  for (SemanticObject& object : frame_.objects) {
    if (static_cast<int>(object.corners.size()) < config_.propagation.max_points_per_object / 4) {
      std::vector<SemanticObject> one{object};
      seed_corners(grey, config_.propagation, one);
      object.corners = one.front().corners;
    }
  }

  // 2. Ask for this frame's segmentation.
  frame_.requested = selector_.next(cues);
  if (frame_.requested != SegmentReason::kNone) {
    requests_.push(Request{frame_index, grey.clone()});
    ++stats_.requests;
  }

  // 3. Finished segmentations (synchronous: wait for this frame's).
  if (config_.fusion.synchronous && frame_.requested != SegmentReason::kNone) {
    while (true) {
      std::optional<Result> r = results_.pop(std::chrono::seconds(60));
      if (!r) break;
      const bool mine = r->frame_index == frame_index;
      adopt(*r);
      if (mine) break;
    }
  }
  while (std::optional<Result> r = results_.try_pop()) adopt(*r);

  for (SemanticObject& object : frame_.objects) ++object.frames_seen;

  // 4. Moving or not.
  static const std::vector<dynamic::TrackedPoint> kNoPoints;
  frame_.votes = motion_.update(geometry ? geometry->points : kNoPoints, geometry ? &geometry->ground_plane : nullptr,
                                frame_.objects);

  // 5. Masks.
  frame_.moving_mask = cv::Mat::zeros(grey.size(), CV_8UC1);
  for (const SemanticObject& object : frame_.objects) {
    if (object.moving) frame_.moving_mask |= object.mask;
  }
  if (config_.fusion.mask_dilation_px > 0) {
    const int r = config_.fusion.mask_dilation_px;
    cv::dilate(frame_.moving_mask, frame_.moving_mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1}));
  }
  const bool has_geometry = geometry && !geometry->mask.image.empty();
  switch (config_.fusion.mode) {
    case FusionMode::kUnion:
      frame_.fused_mask = has_geometry ? (geometry->mask.image | frame_.moving_mask) : frame_.moving_mask.clone();
      break;
    case FusionMode::kSemantic:
      frame_.fused_mask = frame_.moving_mask.clone();
      break;
    case FusionMode::kGeometry:
      frame_.fused_mask = has_geometry ? geometry->mask.image.clone() : cv::Mat::zeros(grey.size(), CV_8UC1);
      break;
  }

  has_previous_ = true;
  frame_.process_ms = ms_since(t0);
  return frame_;
}

void SemanticMasker::apply_fusion(dynamic::DynamicMask& mask) const {
  const SemanticFrame& frame = frame_;
  const FusionMode mode = config_.fusion.mode;
  if (mode == FusionMode::kGeometry || frame.fused_mask.empty()) return;
  const cv::Size size = frame.fused_mask.size();
  if (mode == FusionMode::kSemantic || mask.instances.empty()) {
    mask.instances = cv::Mat::zeros(size, CV_8UC1);
    mask.regions.clear();
  }
  double max_id = 0;
  cv::minMaxLoc(mask.instances, nullptr, &max_id);
  int next_id = static_cast<int>(max_id) + 1;
  const int r = config_.fusion.mask_dilation_px;
  const cv::Mat grow = cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * r + 1, 2 * r + 1});
  for (const SemanticObject& object : frame.objects) {
    if (!object.moving) continue;
    cv::Mat pixels;
    cv::dilate(object.mask, pixels, grow);
    pixels &= frame.fused_mask;
    const cv::Rect box = cv::boundingRect(pixels);
    if (box.empty()) continue;
    // The detector's instance this object overlaps most is the same person or vehicle found by both: the object's
    // other pixels join it, so it is scored and tracked as one object.
    int counts[256] = {0};
    for (int y = box.y; y < box.y + box.height; ++y) {
      const uint8_t* p = pixels.ptr<uint8_t>(y);
      const uint8_t* id = mask.instances.ptr<uint8_t>(y);
      for (int x = box.x; x < box.x + box.width; ++x) counts[p[x] ? id[x] : 0] += p[x] ? 1 : 0;
    }
    const int joined = static_cast<int>(std::max_element(counts + 1, counts + 256) - counts);
    const int id = counts[joined] > 0 ? joined : next_id;
    if (id > 255) continue;
    pixels.setTo(0, mask.instances != 0);
    if (cv::countNonZero(pixels) == 0) continue;
    mask.instances.setTo(id, pixels);
    const cv::Rect added = cv::boundingRect(pixels);
    if (id == next_id) {
      ++next_id;
      mask.regions.push_back(added);
    } else {
      for (cv::Rect& region : mask.regions) {
        if ((region & box).area() > 0) region |= added;
      }
    }
  }
  mask.image = frame.fused_mask.clone();
}

}  // namespace agvslam::semantic
