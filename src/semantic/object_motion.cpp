#include "agvslam/semantic/object_motion.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/median.h"

namespace agvslam::semantic {
namespace {

// The median of a copy (0 for none).
float median_of(std::vector<float> v) { return dynamic::median_in_place(v, 0.f); }

// Which object (index) holds the pixel, -1: none.
int object_at(const std::vector<SemanticObject>& objects, const cv::Point2f& p) {
  const cv::Point px(cvRound(p.x), cvRound(p.y));
  for (std::size_t i = 0; i < objects.size(); ++i) {
    if (objects[i].box.contains(px) && objects[i].mask.at<uint8_t>(px)) return static_cast<int>(i);
  }
  return -1;
}

// Where a static point near `at` with disparity about `disparity_px` moved this frame: the median shift of the
// eight static points nearest in the image among those within 25 % of that disparity (the parallax of a driving
// AGV depends on depth); false when there are fewer than three such points.
bool static_shift_near(const std::vector<const dynamic::TrackedPoint*>& statics, const cv::Point2f& at,
                       double disparity_px, cv::Point2f& shift) {
  std::vector<const dynamic::TrackedPoint*> similar;
  for (const dynamic::TrackedPoint* p : statics) {
    const double d = p->cur_disparity_px;
    if (d > 0 && std::abs(d - disparity_px) <= 0.25 * disparity_px) similar.push_back(p);
  }
  const std::size_t kNearest = 8;
  if (similar.size() < 3) return false;
  const std::size_t n = std::min(kNearest, similar.size());
  std::partial_sort(similar.begin(), similar.begin() + static_cast<std::ptrdiff_t>(n), similar.end(),
                    [&](const dynamic::TrackedPoint* a, const dynamic::TrackedPoint* b) {
                      return cv::norm(a->cur_px - at) < cv::norm(b->cur_px - at);
                    });
  std::vector<float> dx, dy;
  for (std::size_t i = 0; i < n; ++i) {
    dx.push_back(similar[i]->cur_px.x - similar[i]->prev_px.x);
    dy.push_back(similar[i]->cur_px.y - similar[i]->prev_px.y);
  }
  shift = {median_of(dx), median_of(dy)};
  return true;
}

}  // namespace

double ObjectMotionTest::static_threshold_px(const std::vector<float>& static_offsets_px) const {
  if (static_offsets_px.empty()) return config_.min_offset_px;
  const float median = median_of(static_offsets_px);
  std::vector<float> deviation;
  deviation.reserve(static_offsets_px.size());
  for (float v : static_offsets_px) deviation.push_back(std::abs(v - median));
  // 1.4826 MAD is the standard deviation of a normal distribution.
  const double sigma = 1.4826 * median_of(deviation);
  return std::max(config_.min_offset_px, median + config_.static_sigmas * sigma);
}

std::vector<MotionVote> ObjectMotionTest::update(const std::vector<dynamic::TrackedPoint>& points,
                                                 const dynamic::DisparityPlane* ground,
                                                 std::vector<SemanticObject>& objects) const {
  std::vector<int> owner(points.size(), -1);
  std::vector<float> static_offsets;
  std::vector<const dynamic::TrackedPoint*> statics;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const dynamic::TrackedPoint& p = points[i];
    if (!p.tracked) continue;
    owner[i] = object_at(objects, p.cur_px);
    if (owner[i] >= 0 || p.dynamic) continue;
    statics.push_back(&p);
    if (p.reprojection_px >= 0) static_offsets.push_back(static_cast<float>(p.reprojection_px));
  }
  const double threshold = static_threshold_px(static_offsets);

  std::vector<MotionVote> votes(objects.size());
  std::vector<std::vector<float>> disparities(objects.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (owner[i] < 0) continue;
    const dynamic::TrackedPoint& p = points[i];
    MotionVote& v = votes[static_cast<std::size_t>(owner[i])];
    if (p.cur_disparity_px > 0) disparities[static_cast<std::size_t>(owner[i])].push_back(p.cur_disparity_px);
    if (p.reprojection_px < 0 && !p.dynamic_epipolar) continue;
    ++v.tested_points;
    if (p.reprojection_px > threshold || p.dynamic_epipolar || p.dynamic_depth) ++v.moving_points;
  }

  for (std::size_t k = 0; k < objects.size(); ++k) {
    SemanticObject& object = objects[k];
    MotionVote& v = votes[k];
    if (v.tested_points >= config_.min_points) {
      v.measured = true;
      v.vote = v.moving_points >= config_.moving_fraction * v.tested_points ? 1.0 : 0.0;
    } else if (object.flow_known) {
      const cv::Moments m = cv::moments(object.mask, true);
      const cv::Point2f centre = m.m00 > 0
                                     ? cv::Point2f(static_cast<float>(m.m10 / m.m00), static_cast<float>(m.m01 / m.m00))
                                     : cv::Point2f(0, 0);
      // Its depth: its own points', else the floor's below the middle of its box (where it stands).
      double disparity = median_of(disparities[k]);
      if (disparity <= 0 && ground && ground->valid) {
        disparity = ground->disparity_at(object.box.x + 0.5 * object.box.width, object.box.y + object.box.height - 1);
      }
      cv::Point2f static_shift;
      if (disparity > 0 && static_shift_near(statics, centre, disparity, static_shift)) {
        v.from_mask = v.measured = true;
        v.mask_offset_px = cv::norm(object.flow_px - static_shift);
        v.vote = v.mask_offset_px > config_.far_min_offset_px ? 1.0 : 0.0;
      }
    }
    object.evidence = config_.decay * object.evidence + v.vote;
    if (!object.moving && object.evidence > config_.enter_evidence) object.moving = true;
    if (object.moving && object.evidence < config_.exit_evidence) object.moving = false;
  }
  return votes;
}

}  // namespace agvslam::semantic
