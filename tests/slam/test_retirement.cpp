// Point retirement (point_retirement.h) on a synthetic map: a textured wall 8 m ahead and a textured box 3 m ahead,
// both mapped from one keyframe, rendered as a rectified stereo pair by ray casting. The box then moves (inside
// the dynamic mask) or is carried away; an occluder 1.5 m ahead hides part of the
// wall for a while; the wall's points are matched with a little pixel noise throughout.

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <optional>
#include <random>

#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/map_io.h"
#include "agvslam/slam/map_point.h"
#include "agvslam/slam/point_retirement.h"
#include "synthetic_world.h"

namespace agvslam::slam {
namespace {

// Smooth random texture: value noise on a 4 cm lattice, grey levels 30-225.
double texture(double x_m, double y_m, int surface) {
  auto lattice = [surface](int64_t i, int64_t j) {
    uint64_t h = static_cast<uint64_t>(i) * 0x9E3779B97F4A7C15ULL ^ static_cast<uint64_t>(j) * 0xC2B2AE3D27D4EB4FULL ^
                 static_cast<uint64_t>(surface) * 0x165667B19E3779F9ULL;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ULL;
    h ^= h >> 32;
    return static_cast<double>(h % 1000) / 999.0;
  };
  const double s = 0.04;
  const double gx = x_m / s, gy = y_m / s;
  const int64_t i = static_cast<int64_t>(std::floor(gx)), j = static_cast<int64_t>(std::floor(gy));
  const double fx = gx - static_cast<double>(i), fy = gy - static_cast<double>(j);
  const double a = lattice(i, j), b = lattice(i + 1, j), c = lattice(i, j + 1), d = lattice(i + 1, j + 1);
  return 30.0 + 195.0 * ((a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy);
}

constexpr double kWallZ = 8.0, kBoxZ = 3.0, kOccluderZ = 1.5;

struct Scene {
  std::optional<double> box_x;       // centre of the box's 1 m x 1 m front face (absent: carried away)
  std::optional<double> occluder_x;  // left edge of a 0.5 m wide occluder, full height
  // Ray (origin o, direction d with d.z = 1) against the scene, nearest surface first: grey level and id.
  double shade(const Eigen::Vector3d& o, const Eigen::Vector3d& d, int* surface_id = nullptr) const {
    auto hit = [&](double z) { return Eigen::Vector3d(o + d * (z - o.z())); };
    if (occluder_x) {
      const Eigen::Vector3d p = hit(kOccluderZ);
      if (p.x() >= *occluder_x && p.x() <= *occluder_x + 0.5) {
        if (surface_id) *surface_id = 3;
        return texture(p.x(), p.y(), 3);
      }
    }
    if (box_x) {
      const Eigen::Vector3d p = hit(kBoxZ);
      if (std::fabs(p.x() - *box_x) <= 0.5 && std::fabs(p.y()) <= 0.5) {
        if (surface_id) *surface_id = 2;
        return texture(p.x() - *box_x, p.y(), 2);  // the texture moves with the box
      }
    }
    const Eigen::Vector3d p = hit(kWallZ);
    if (surface_id) *surface_id = 1;
    return texture(p.x(), p.y(), 1);
  }
};

// The camera sits at the world origin (left) looking along z; the right camera is baseline_m along x. Sensor
// noise of 2 grey levels (the simulator's), seeded by `frame`.
FrameImages render(const Scene& scene, const FrameGeometry& g, bool mask_box, uint64_t frame = 0) {
  std::mt19937 rng(static_cast<uint32_t>(frame) + 1000);
  std::normal_distribution<double> noise(0.0, 2.0);
  const PinholeCamera& cam = g.camera;
  FrameImages out;
  out.left.create(cam.height, cam.width, CV_8UC1);
  out.right.create(cam.height, cam.width, CV_8UC1);
  out.dynamic_mask = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
      int surface = 0;
      out.left.at<uint8_t>(v, u) =
          cv::saturate_cast<uint8_t>(scene.shade(Eigen::Vector3d::Zero(), d, &surface) + noise(rng));
      if (mask_box && surface == 2) out.dynamic_mask.at<uint8_t>(v, u) = 255;
      out.right.at<uint8_t>(v, u) =
          cv::saturate_cast<uint8_t>(scene.shade(Eigen::Vector3d(g.baseline_m, 0, 0), d) + noise(rng));
    }
  }
  return out;
}

// Points on the wall and on the box (at box_x = 0), mapped from one keyframe at the origin.
class SyntheticMap : public ::testing::Test {
 protected:
  void SetUp() override {
    geometry_ = test::test_geometry();
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> wall_x(-3.5, 3.5), wall_y(-2.0, 2.0), box(-0.4, 0.4);
    for (int k = 0; k < 120; ++k) points_w_.emplace_back(wall_x(rng), wall_y(rng), kWallZ);
    n_wall_ = points_w_.size();
    for (int k = 0; k < 40; ++k) points_w_.emplace_back(box(rng), box(rng), kBoxZ);
    // Wall points hidden by the box at mapping time are not mapped.
    std::vector<Eigen::Vector3d> visible;
    std::size_t wall = 0;
    for (std::size_t k = 0; k < points_w_.size(); ++k) {
      const Eigen::Vector3d& p = points_w_[k];
      const bool behind_box =
          k < n_wall_ && std::fabs(p.x() * kBoxZ / kWallZ) <= 0.55 && std::fabs(p.y() * kBoxZ / kWallZ) <= 0.55;
      if (behind_box) continue;
      visible.push_back(p);
      if (k < n_wall_) ++wall;
    }
    points_w_ = visible;
    n_wall_ = wall;
    test::World world;
    world.points_w = points_w_;
    world.descriptors.assign(points_w_.size(), Descriptor{});
    std::vector<int> point_of_keypoint;
    Frame frame;
    test::make_frame(world, SE3d::Identity(), geometry_, 0, 0.0, 1, frame, point_of_keypoint);
    ASSERT_EQ(point_of_keypoint.size(), points_w_.size());
    keyframe_ = std::make_shared<KeyFrame>(map_.new_keyframe_id(), frame);
    map_.add_keyframe(keyframe_);
    for (std::size_t i = 0; i < frame.size(); ++i) {
      auto p = std::make_shared<MapPoint>(
          map_.new_map_point_id(), points_w_[static_cast<std::size_t>(point_of_keypoint[i])], keyframe_.get(), 0);
      p->add_observation(keyframe_.get(), static_cast<int>(i));
      keyframe_->add_map_point(p, i);
      p->compute_distinctive_descriptor();
      p->update_normal_and_depth();
      map_.add_map_point(p);
      points_.push_back(p);
    }
  }

  // One tracked frame at the origin: `matched(k)` gives the pixel offsets (u, v, u_right) of point k's match, or
  // nothing when it is not matched. Returns the points retired.
  RetirementCounts step(uint64_t frame_id, const FrameImages& images,
                        const std::function<std::optional<Eigen::Vector3d>(std::size_t)>& matched) {
    std::vector<cv::KeyPoint> kps;
    std::vector<float> u_right, depth;
    std::vector<std::size_t> point_of;
    for (std::size_t k = 0; k < points_.size(); ++k) {
      if (points_[k]->bad()) continue;
      const std::optional<Eigen::Vector3d> offset = matched(k);
      if (!offset) continue;
      const Eigen::Vector3d& p = points_w_[k];
      const Eigen::Vector2d uv_true = geometry_->camera.project(p);
      const Eigen::Vector2d uv = uv_true + offset->head<2>();
      kps.emplace_back(static_cast<float>(uv.x()), static_cast<float>(uv.y()), 31.f, 0.f, 1.f, 0);
      const double disparity = geometry_->bf / p.z();
      u_right.push_back(static_cast<float>(uv_true.x() - disparity + offset->z()));
      depth.push_back(static_cast<float>(p.z()));
      point_of.push_back(k);
    }
    Frame frame;
    frame.assign(frame_id, static_cast<int64_t>(frame_id) * 50'000'000, geometry_, kps,
                 cv::Mat::zeros(static_cast<int>(kps.size()), 32, CV_8UC1), u_right, depth);
    frame.set_pose(SE3d::Identity());
    std::vector<PointRetirement::Match> matches;
    for (std::size_t i = 0; i < point_of.size(); ++i) matches.push_back({points_[point_of[i]], static_cast<int>(i)});
    std::vector<MapPoint*> local;
    for (const MapPointPtr& p : points_) {
      if (!p->bad()) local.push_back(p.get());
    }
    return retirement_.update(frame, matches, local, images, map_);
  }

  std::size_t retired_wall() const {
    std::size_t n = 0;
    for (std::size_t k = 0; k < n_wall_; ++k) n += points_[k]->bad() ? 1 : 0;
    return n;
  }
  std::size_t retired_box() const {
    std::size_t n = 0;
    for (std::size_t k = n_wall_; k < points_.size(); ++k) n += points_[k]->bad() ? 1 : 0;
    return n;
  }
  std::size_t box_points() const { return points_.size() - n_wall_; }
  bool on_wall(std::size_t k) const { return k < n_wall_; }

  // The wall's points matched with 1 px noise (left and right image independent); the box's as `box` says.
  std::function<std::optional<Eigen::Vector3d>(std::size_t)> wall_noise_and(
      std::function<std::optional<Eigen::Vector3d>(std::size_t)> box, uint32_t seed) {
    auto rng = std::make_shared<std::mt19937>(seed);
    return [this, rng, box](std::size_t k) -> std::optional<Eigen::Vector3d> {
      if (!on_wall(k)) return box(k);
      std::normal_distribution<double> n(0.0, 1.0);
      return Eigen::Vector3d(n(*rng), n(*rng), n(*rng));
    };
  }

  FrameGeometryPtr geometry_;
  Map map_;
  KeyFramePtr keyframe_;
  std::vector<Eigen::Vector3d> points_w_;
  std::size_t n_wall_ = 0;
  std::vector<MapPointPtr> points_;
  static RetirementConfig enabled_config() {
    RetirementConfig c;
    c.enabled = true;  // the default; these tests are about the capability whatever the default
    return c;
  }
  PointRetirement retirement_{enabled_config(), StereoIntrinsics{460, 460, 376, 240, 460 * 0.12}};
};

TEST(ProbeStereo, TellsASurfaceAtTheDepthBehindAndInFront) {
  const FrameGeometryPtr g = test::test_geometry();
  Scene scene;
  scene.box_x = 0.0;
  const FrameImages im = render(scene, *g, false);
  const RetirementConfig c;
  const double box_d = g->bf / kBoxZ, wall_d = g->bf / kWallZ, tol = 3.6;
  // The box's centre; a wall pixel well left of the box.
  EXPECT_EQ(probe_stereo(im.left, im.right, 376, 240, box_d, tol, c), SurfaceAt::kAtDepth);
  EXPECT_EQ(probe_stereo(im.left, im.right, 376, 240, wall_d, tol, c), SurfaceAt::kInFront);
  EXPECT_EQ(probe_stereo(im.left, im.right, 120, 240, wall_d, tol, c), SurfaceAt::kAtDepth);
  EXPECT_EQ(probe_stereo(im.left, im.right, 120, 240, box_d, tol, c), SurfaceAt::kBehind);
  // No texture, or outside the image: nothing to say.
  const cv::Mat flat(g->camera.height, g->camera.width, CV_8UC1, cv::Scalar(128));
  EXPECT_EQ(probe_stereo(flat, flat, 376, 240, box_d, tol, c), SurfaceAt::kUnknown);
  EXPECT_EQ(probe_stereo(im.left, im.right, 1, 240, box_d, tol, c), SurfaceAt::kUnknown);
  // Textured, but the right image shows something else at every disparity (the box's texture against a flat right
  // image with one vertical edge): no match.
  cv::Mat other(g->camera.height, g->camera.width, CV_8UC1, cv::Scalar(60));
  other(cv::Rect(0, 0, 200, g->camera.height)).setTo(200);
  EXPECT_EQ(probe_stereo(im.left, other, 376, 240, box_d, tol, c), SurfaceAt::kNoMatch);
}

TEST_F(SyntheticMap, ABoxThatStartsMovingInTheMaskIsRetiredWithinAFewFrames) {
  Scene scene;
  scene.box_x = 0.0;
  uint64_t id = 1;
  // Standing: every point matched, nothing retired.
  for (; id <= 5; ++id) {
    step(id, render(scene, *geometry_, false, id),
         wall_noise_and([](std::size_t) { return Eigen::Vector3d::Zero(); }, static_cast<uint32_t>(id)));
  }
  EXPECT_EQ(retired_box(), 0u);
  // Moving 2 cm per frame to the side, masked, its keypoints not extracted.
  RetirementCounts total;
  uint64_t frames_moving = 0;
  for (; retired_box() < box_points() && frames_moving < 60; ++id, ++frames_moving) {
    *scene.box_x += 0.02;
    total += step(id, render(scene, *geometry_, true, id),
                  wall_noise_and([](std::size_t) { return std::nullopt; }, 100 + static_cast<uint32_t>(id)));
  }
  // Evidence starts as soon as the surface at a point's pixel has moved on by about a texture cell (at half a cell
  // per frame a patch still resembles the last frame's): the box's texture at its depth in the mask, or, where the
  // stereo correlation of the shifted texture peaks elsewhere, no match or a surface behind; a point goes once the
  // wall is seen where it was, when the box's trailing edge has passed it: after at most the box's 1 m width at 2 cm
  // per frame.
  EXPECT_EQ(retired_box(), box_points());
  EXPECT_LE(frames_moving, 52u);
  EXPECT_EQ(total.total(), box_points());
  EXPECT_EQ(retired_wall(), 0u);
  // Their keyframe keypoints are blocked: nothing can bring them back.
  for (std::size_t i = 0; i < keyframe_->size(); ++i) {
    const MapPointPtr& p = keyframe_->map_point(i);
    if (!p) {
      EXPECT_TRUE(keyframe_->keypoint_retired(i)) << "keypoint " << i;
    }
  }
  EXPECT_EQ(keyframe_->retired_keypoint_count(), box_points());
  EXPECT_EQ(map_.map_point_count(), n_wall_);
}

TEST_F(SyntheticMap, ABoxCarriedAwayIsRetiredBecauseTheWallIsSeenBehindIt) {
  Scene scene;
  scene.box_x = 0.0;
  uint64_t id = 1;
  // Standing and matched: the points learn what their surface looks like.
  for (; id <= 3; ++id) {
    step(id, render(scene, *geometry_, false, id), [](std::size_t) { return Eigen::Vector3d::Zero(); });
  }
  scene.box_x.reset();  // carried away, nothing is masked
  RetirementCounts total;
  const uint64_t gone = id;
  for (; id < gone + 6; ++id) {
    total += step(id, render(scene, *geometry_, false, id),
                  wall_noise_and([](std::size_t) { return std::nullopt; }, static_cast<uint32_t>(id)));
  }
  // A point where the wall behind happens to look like the box (ZNCC >= 0.8 on this smooth texture, one cell per
  // 6 px) cannot be told from one that is still there.
  EXPECT_GE(retired_box(), box_points() - 1);
  EXPECT_EQ(total.absent, retired_box());
  EXPECT_EQ(retired_wall(), 0u);
}

TEST_F(SyntheticMap, StaticNoisyPointsAndPointsOccludedForAWhileStay) {
  Scene scene;
  scene.box_x = 0.0;
  std::mt19937 rng(3);
  std::bernoulli_distribution missed(0.3);
  uint64_t id = 1;
  // 100 frames of 1 px noise with 30 % of the matches missed (the probe sees the point's surface then).
  for (; id <= 100; ++id) {
    step(id, render(scene, *geometry_, false, id), [&](std::size_t) -> std::optional<Eigen::Vector3d> {
      if (missed(rng)) return std::nullopt;
      std::normal_distribution<double> n(0.0, 1.0);
      return Eigen::Vector3d(n(rng), n(rng), n(rng));
    });
  }
  EXPECT_EQ(retired_wall() + retired_box(), 0u);
  // An occluder (a person walking past, masked and unmasked) hides the left part of the wall for 30 frames.
  scene.occluder_x = -1.0;
  auto hidden = [&](std::size_t k) {
    const Eigen::Vector3d& p = points_w_[k];
    const double x_at_occluder = p.x() * kOccluderZ / p.z();
    return x_at_occluder >= -1.0 - 0.02 && x_at_occluder <= -0.5 + 0.02;
  };
  std::size_t n_hidden = 0;
  for (std::size_t k = 0; k < points_.size(); ++k) n_hidden += hidden(k) ? 1 : 0;
  ASSERT_GE(n_hidden, 5u);
  for (int f = 0; f < 30; ++f, ++id) {
    FrameImages im = render(scene, *geometry_, false, id);
    if (f % 2 == 1) {
      // Every other frame the occluder is in the mask (a detector that flags it now and then).
      const int u0 = static_cast<int>(geometry_->camera.cx + geometry_->camera.fx * -1.0 / kOccluderZ);
      const int u1 = static_cast<int>(geometry_->camera.cx + geometry_->camera.fx * -0.5 / kOccluderZ);
      im.dynamic_mask.colRange(u0, u1 + 1).setTo(255);
    }
    step(id, im, [&](std::size_t k) -> std::optional<Eigen::Vector3d> {
      if (hidden(k)) return std::nullopt;
      return Eigen::Vector3d::Zero();
    });
  }
  scene.occluder_x.reset();
  for (int f = 0; f < 10; ++f, ++id) {
    step(id, render(scene, *geometry_, false, id), [](std::size_t) { return Eigen::Vector3d::Zero(); });
  }
  EXPECT_EQ(retired_wall() + retired_box(), 0u);
}

TEST_F(SyntheticMap, StaticPointsInAFalseMaskRegionOrMismatchedStay) {
  Scene scene;
  scene.box_x = 0.0;
  uint64_t id = 1;
  for (; id <= 3; ++id) {
    step(id, render(scene, *geometry_, false, id), [](std::size_t) { return Eigen::Vector3d::Zero(); });
  }
  // For 12 frames a detector flags the left half of the static scene (its keypoints are not extracted there), and
  // the right half's points are matched 6 px off (a repeated texture): nothing moved, nothing may be retired.
  const int u_half = static_cast<int>(geometry_->camera.cx);
  for (int f = 0; f < 12; ++f, ++id) {
    FrameImages im = render(scene, *geometry_, false, id);
    im.dynamic_mask.colRange(0, u_half).setTo(255);
    step(id, im, [&](std::size_t k) -> std::optional<Eigen::Vector3d> {
      if (geometry_->camera.project(points_w_[k]).x() < u_half + 8) return std::nullopt;
      return Eigen::Vector3d(6.0, 0.0, 6.0);
    });
  }
  EXPECT_EQ(retired_wall() + retired_box(), 0u);
}

TEST_F(SyntheticMap, RetiredKeypointsStayBlockedInASavedMap) {
  Scene scene;
  scene.box_x = 0.0;
  step(1, render(scene, *geometry_, false, 1), [](std::size_t) { return Eigen::Vector3d::Zero(); });
  scene.box_x.reset();  // carried away
  for (uint64_t id = 2; retired_box() < box_points() && id <= 10; ++id) {
    step(id, render(scene, *geometry_, false, id),
         wall_noise_and([](std::size_t) { return std::nullopt; }, static_cast<uint32_t>(id)));
  }
  ASSERT_EQ(keyframe_->retired_keypoint_count(), box_points());
  const MapFileContext context = MapFileContext::from(*geometry_, 0, 2);
  const std::string bytes = encode_map(map_, context);
  Map loaded;
  decode_map(bytes, "test", context, geometry_, loaded);
  const KeyFramePtr kf = loaded.keyframe(keyframe_->id);
  ASSERT_TRUE(kf);
  EXPECT_EQ(kf->retired_keypoint_count(), box_points());
  EXPECT_EQ(loaded.map_point_count(), n_wall_);
  for (std::size_t i = 0; i < kf->size(); ++i) {
    if (kf->keypoint_retired(i)) {
      EXPECT_FALSE(kf->map_point(i));
    }
  }
}

}  // namespace
}  // namespace agvslam::slam
