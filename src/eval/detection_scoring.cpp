#include "agvslam/eval/detection_scoring.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>
#include <tuple>

namespace agvslam::eval {
namespace {

struct ObjectPixels {
  int id = 0;
  cv::Rect box;
  int pixels = 0;
  bool ignored = false;
};

}  // namespace

namespace {

FrameDetectionScore score_labelled(const cv::Mat& det_labels, int n_labels, const cv::Mat& gt_mask,
                                   const std::vector<GroundTruthObject>& objects, const DetectionScoringConfig& config,
                                   const cv::Mat& gt_instances);

void check_gt_instances(const cv::Mat& gt_instances, const cv::Mat& gt_mask, const char* function) {
  if (gt_instances.empty()) return;
  if (gt_instances.type() != CV_8UC1 || gt_instances.size() != gt_mask.size()) {
    throw std::invalid_argument(std::string(function) +
                                ": expected CV_8UC1 ground-truth instances of the mask's size " +
                                std::to_string(gt_mask.cols) + "x" + std::to_string(gt_mask.rows) + ", got " +
                                std::to_string(gt_instances.cols) + "x" + std::to_string(gt_instances.rows));
  }
}

}  // namespace

FrameDetectionScore score_detections(const cv::Mat& detected_mask, const cv::Mat& gt_mask,
                                     const std::vector<GroundTruthObject>& objects,
                                     const DetectionScoringConfig& config, const cv::Mat& gt_instances) {
  if (detected_mask.type() != CV_8UC1 || gt_mask.type() != CV_8UC1 || detected_mask.size() != gt_mask.size()) {
    throw std::invalid_argument("score_detections: expected two CV_8UC1 masks of one size, got " +
                                std::to_string(detected_mask.cols) + "x" + std::to_string(detected_mask.rows) +
                                " and " + std::to_string(gt_mask.cols) + "x" + std::to_string(gt_mask.rows));
  }
  check_gt_instances(gt_instances, gt_mask, "score_detections");
  cv::Mat labels;
  const int n = cv::connectedComponents(detected_mask, labels, 8, CV_32S);
  return score_labelled(labels, n, gt_mask, objects, config, gt_instances);
}

FrameDetectionScore score_detection_instances(const cv::Mat& detection_labels, const cv::Mat& gt_mask,
                                              const std::vector<GroundTruthObject>& objects,
                                              const DetectionScoringConfig& config, const cv::Mat& gt_instances) {
  if ((detection_labels.type() != CV_8UC1 && detection_labels.type() != CV_32SC1) || gt_mask.type() != CV_8UC1 ||
      detection_labels.size() != gt_mask.size()) {
    throw std::invalid_argument(
        "score_detection_instances: expected CV_8UC1/CV_32SC1 labels and a CV_8UC1 mask of one "
        "size, got " +
        std::to_string(detection_labels.cols) + "x" + std::to_string(detection_labels.rows) + " and " +
        std::to_string(gt_mask.cols) + "x" + std::to_string(gt_mask.rows));
  }
  check_gt_instances(gt_instances, gt_mask, "score_detection_instances");
  cv::Mat labels;
  detection_labels.convertTo(labels, CV_32S);
  double max_label = 0;
  cv::minMaxLoc(labels, nullptr, &max_label);
  return score_labelled(labels, static_cast<int>(max_label) + 1, gt_mask, objects, config, gt_instances);
}

namespace {

FrameDetectionScore score_labelled(const cv::Mat& det_labels, int n_labels, const cv::Mat& gt_mask,
                                   const std::vector<GroundTruthObject>& objects, const DetectionScoringConfig& config,
                                   const cv::Mat& gt_instances) {
  FrameDetectionScore score;
  const cv::Rect frame_rect(0, 0, gt_mask.cols, gt_mask.rows);

  // Detected objects: the non-empty labels 1 .. n_labels-1, with their boxes and areas.
  std::vector<int> area(static_cast<std::size_t>(std::max(n_labels, 1)), 0);
  std::vector<int> x0(area.size(), 1 << 30), y0(area.size(), 1 << 30), x1(area.size(), -1), y1(area.size(), -1);
  for (int y = 0; y < det_labels.rows; ++y) {
    const int* l = det_labels.ptr<int>(y);
    for (int x = 0; x < det_labels.cols; ++x) {
      const int k = l[x];
      if (k <= 0 || k >= n_labels) continue;
      const auto u = static_cast<std::size_t>(k);
      ++area[u];
      x0[u] = std::min(x0[u], x);
      y0[u] = std::min(y0[u], y);
      x1[u] = std::max(x1[u], x);
      y1[u] = std::max(y1[u], y);
    }
  }
  std::vector<int> det_index(area.size(), -1);  // label -> detection
  for (int k = 1; k < n_labels; ++k) {
    const auto u = static_cast<std::size_t>(k);
    if (area[u] == 0) continue;
    DetectedObject d;
    d.box = cv::Rect(cv::Point(x0[u], y0[u]), cv::Point(x1[u] + 1, y1[u] + 1));
    d.pixels = area[u];
    d.ignored = d.pixels < config.min_detection_pixels;
    det_index[u] = static_cast<int>(score.detections.size());
    score.detections.push_back(d);
  }
  cv::Mat detected_mask = det_labels > 0;

  // Ground-truth objects.
  std::vector<ObjectPixels> gt;
  cv::Mat gt_labels;  // only when the objects come from the mask itself
  if (objects.empty()) {
    cv::Mat gt_stats, gt_centroids;
    const int n = cv::connectedComponentsWithStats(gt_mask, gt_labels, gt_stats, gt_centroids, 8, CV_32S);
    for (int k = 1; k < n; ++k) {
      gt.push_back({k,
                    cv::Rect(gt_stats.at<int>(k, cv::CC_STAT_LEFT), gt_stats.at<int>(k, cv::CC_STAT_TOP),
                             gt_stats.at<int>(k, cv::CC_STAT_WIDTH), gt_stats.at<int>(k, cv::CC_STAT_HEIGHT)),
                    0, false});
    }
  } else {
    for (const auto& o : objects) gt.push_back({o.id, o.box & frame_rect, 0, false});
  }

  // Intersections object x detection, counted over each object's box.
  const std::size_t n_det = score.detections.size();
  std::vector<std::vector<int>> inter(gt.size(), std::vector<int>(n_det, 0));
  for (std::size_t g = 0; g < gt.size(); ++g) {
    const cv::Rect& box = gt[g].box;
    for (int y = box.y; y < box.y + box.height; ++y) {
      const uint8_t* m = gt_mask.ptr<uint8_t>(y);
      const int* dl = det_labels.ptr<int>(y);
      const int* gl = gt_labels.empty() ? nullptr : gt_labels.ptr<int>(y);
      // An object's own pixels: where instances are known, those carrying its id.
      const uint8_t* gi = gl == nullptr && !gt_instances.empty() ? gt_instances.ptr<uint8_t>(y) : nullptr;
      for (int x = box.x; x < box.x + box.width; ++x) {
        if (!m[x] || (gl && gl[x] != gt[g].id) || (gi && gi[x] != gt[g].id)) continue;
        ++gt[g].pixels;
        if (dl[x] > 0 && dl[x] < n_labels && det_index[static_cast<std::size_t>(dl[x])] >= 0) {
          ++inter[g][static_cast<std::size_t>(det_index[static_cast<std::size_t>(dl[x])])];
        }
      }
    }
    gt[g].ignored = gt[g].pixels == 0 || gt[g].pixels < config.min_object_pixels;
  }

  // One-to-one matching, best IoU first.
  std::vector<std::tuple<double, std::size_t, std::size_t>> candidates;
  for (std::size_t g = 0; g < gt.size(); ++g) {
    for (std::size_t k = 0; k < n_det; ++k) {
      if (inter[g][k] == 0 || score.detections[k].ignored) continue;
      const double uni = static_cast<double>(gt[g].pixels) + score.detections[k].pixels - inter[g][k];
      const double iou = inter[g][k] / uni;
      if (iou >= config.min_iou) candidates.emplace_back(iou, g, k);
    }
  }
  std::sort(candidates.begin(), candidates.end(),
            [](const auto& a, const auto& b) { return std::get<0>(a) > std::get<0>(b); });
  std::vector<bool> gt_matched(gt.size(), false);
  for (const auto& [iou, g, k] : candidates) {
    DetectedObject& d = score.detections[k];
    if (gt_matched[g] || d.matched_object_id != -1) continue;
    gt_matched[g] = true;
    d.matched_object_id = gt[g].id;
    d.iou = iou;
    if (gt[g].ignored) {
      d.ignored = true;  // a detected "don't care" object: neither TP nor FP
    } else {
      ++score.true_positives;
      score.matched_iou.push_back(iou);
    }
  }
  for (std::size_t g = 0; g < gt.size(); ++g) {
    if (gt[g].ignored) {
      ++score.ignored_objects;
    } else if (!gt_matched[g]) {
      ++score.false_negatives;
      score.missed_object_ids.push_back(gt[g].id);
    }
  }
  for (std::size_t k = 0; k < n_det; ++k) {
    DetectedObject& d = score.detections[k];
    if (d.matched_object_id != -1 || d.ignored) {
      if (d.ignored) ++score.ignored_detections;
      continue;
    }
    int on_ignored = 0;
    for (std::size_t g = 0; g < gt.size(); ++g) {
      if (gt[g].ignored) on_ignored += inter[g][k];
    }
    if (2 * on_ignored >= d.pixels) {
      d.ignored = true;
      ++score.ignored_detections;
    } else {
      ++score.false_positives;
    }
  }

  cv::Mat both;
  cv::bitwise_and(detected_mask, gt_mask, both);
  score.pixels_detected = cv::countNonZero(detected_mask);
  score.pixels_ground_truth = cv::countNonZero(gt_mask);
  score.pixels_intersection = cv::countNonZero(both);
  return score;
}

}  // namespace

void DetectionScore::add(const FrameDetectionScore& f) {
  ++frames_;
  tp_ += f.true_positives;
  fp_ += f.false_positives;
  fn_ += f.false_negatives;
  ignored_objects_ += f.ignored_objects;
  for (double iou : f.matched_iou) iou_sum_ += iou;
  pix_det_ += f.pixels_detected;
  pix_gt_ += f.pixels_ground_truth;
  pix_inter_ += f.pixels_intersection;
}

double DetectionScore::pixel_precision() const {
  return pix_det_ > 0 ? static_cast<double>(pix_inter_) / static_cast<double>(pix_det_) : 1.0;
}
double DetectionScore::pixel_recall() const {
  return pix_gt_ > 0 ? static_cast<double>(pix_inter_) / static_cast<double>(pix_gt_) : 1.0;
}
double DetectionScore::pixel_iou() const {
  const int64_t uni = pix_det_ + pix_gt_ - pix_inter_;
  return uni > 0 ? static_cast<double>(pix_inter_) / static_cast<double>(uni) : 1.0;
}

}  // namespace agvslam::eval
