#include "agvslam/semantic/mask_propagation.h"

#include <algorithm>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "agvslam/dynamic/median.h"

namespace agvslam::semantic {
namespace {

cv::Size lk_window(const PropagationConfig& config) { return {config.lk_window_px, config.lk_window_px}; }

}  // namespace

std::vector<SemanticObject> extract_objects(const cv::Mat& labels, const std::vector<int>& movable_ids,
                                            int min_object_pixels) {
  std::vector<SemanticObject> objects;
  cv::Mat component_ids, stats, centroids;
  for (int class_id : movable_ids) {
    const cv::Mat of_class = labels == class_id;
    const int n = cv::connectedComponentsWithStats(of_class, component_ids, stats, centroids, 8, CV_32S);
    for (int c = 1; c < n; ++c) {
      if (stats.at<int>(c, cv::CC_STAT_AREA) < min_object_pixels) continue;
      SemanticObject object;
      object.class_id = class_id;
      object.mask = component_ids == c;
      object.box = cv::Rect(stats.at<int>(c, cv::CC_STAT_LEFT), stats.at<int>(c, cv::CC_STAT_TOP),
                            stats.at<int>(c, cv::CC_STAT_WIDTH), stats.at<int>(c, cv::CC_STAT_HEIGHT));
      objects.push_back(std::move(object));
    }
  }
  return objects;
}

void seed_corners(const cv::Mat& grey, const PropagationConfig& config, std::vector<SemanticObject>& objects) {
  static const cv::Mat kErode = cv::getStructuringElement(cv::MORPH_RECT, {5, 5});
  for (SemanticObject& object : objects) {
    object.corners.clear();
    // Within the object's box only: the corner response of the whole frame would cost the caller's thread.
    const cv::Rect box = cv::boundingRect(object.mask);
    if (box.empty()) continue;
    cv::Mat inner;
    cv::erode(object.mask(box), inner, kErode);
    if (cv::countNonZero(inner) == 0) inner = object.mask(box).clone();
    // Corners at least 3 px apart, any with 1 % of the strongest response: people's clothing is low in contrast.
    cv::goodFeaturesToTrack(grey(box), object.corners, config.max_points_per_object, 0.01, 3.0, inner);
    for (cv::Point2f& c : object.corners) c += cv::Point2f(static_cast<float>(box.x), static_cast<float>(box.y));
    const int wanted = config.max_points_per_object / 2;
    if (static_cast<int>(object.corners.size()) >= wanted) continue;
    const int step = std::max(2, static_cast<int>(std::sqrt(static_cast<double>(box.area()) / std::max(1, wanted))));
    for (int y = box.y + step / 2; y < box.y + box.height; y += step) {
      for (int x = box.x + step / 2; x < box.x + box.width; x += step) {
        if (inner.at<uint8_t>(y - box.y, x - box.x)) {
          object.corners.emplace_back(static_cast<float>(x), static_cast<float>(y));
        }
      }
    }
  }
}

std::vector<cv::Mat> lk_pyramid(const cv::Mat& grey, const PropagationConfig& config) {
  std::vector<cv::Mat> pyramid;
  cv::buildOpticalFlowPyramid(grey, pyramid, lk_window(config), config.lk_levels - 1);
  return pyramid;
}

void carry_objects(const std::vector<cv::Mat>& from, const std::vector<cv::Mat>& to, const PropagationConfig& config,
                   std::vector<SemanticObject>& objects) {
  std::vector<cv::Point2f> before;
  for (const SemanticObject& object : objects)
    before.insert(before.end(), object.corners.begin(), object.corners.end());
  std::vector<cv::Point2f> after, back;
  std::vector<uint8_t> ok, ok_back;
  std::vector<float> err;
  if (!before.empty()) {
    const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 0.01);
    cv::calcOpticalFlowPyrLK(from, to, before, after, ok, err, lk_window(config), config.lk_levels - 1, stop);
    cv::calcOpticalFlowPyrLK(to, from, after, back, ok_back, err, lk_window(config), config.lk_levels - 1, stop);
  }
  const cv::Size size = to[0].size();
  const cv::Rect frame(0, 0, size.width, size.height);
  std::size_t k = 0;
  std::vector<SemanticObject> kept;
  for (SemanticObject& object : objects) {
    std::vector<cv::Point2f> src, dst;
    for (std::size_t i = 0; i < object.corners.size(); ++i, ++k) {
      const double fb = cv::norm(back[k] - before[k]);
      if (ok[k] && ok_back[k] && fb <= config.max_fb_error_px && frame.contains(after[k])) {
        src.push_back(before[k]);
        dst.push_back(after[k]);
      }
    }
    object.flow_known = !src.empty();
    cv::Mat warp;
    if (src.size() >= 3) {
      std::vector<uint8_t> inliers;
      warp = cv::estimateAffinePartial2D(src, dst, inliers, cv::RANSAC, 2.0);
    }
    std::vector<float> dx, dy;
    for (std::size_t i = 0; i < src.size(); ++i) {
      dx.push_back(dst[i].x - src[i].x);
      dy.push_back(dst[i].y - src[i].y);
    }
    object.flow_px = {dynamic::median_in_place(dx, 0.f), dynamic::median_in_place(dy, 0.f)};
    if (warp.empty()) warp = (cv::Mat_<double>(2, 3) << 1, 0, object.flow_px.x, 0, 1, object.flow_px.y);
    cv::Mat moved;
    cv::warpAffine(object.mask, moved, warp, size, cv::INTER_NEAREST, cv::BORDER_CONSTANT, 0);
    object.mask = moved;
    object.box = cv::boundingRect(object.mask);
    object.corners = dst;
    if (cv::countNonZero(object.mask) >= config.min_object_pixels) kept.push_back(std::move(object));
  }
  objects = std::move(kept);
}

double mask_iou(const cv::Mat& a, const cv::Mat& b) {
  const int inter = cv::countNonZero(a & b);
  const int uni = cv::countNonZero(a | b);
  return uni == 0 ? 0.0 : static_cast<double>(inter) / uni;
}

}  // namespace agvslam::semantic
