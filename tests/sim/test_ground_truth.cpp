// The rendered images agree with their ground truth: disparity = fx * baseline / depth of an independent ray
// cast, SGBM on the rendered pair recovers that disparity, the motion mask covers exactly the moving actors,
// and feature tracking + PnP on the images recovers the relative motion in poses.txt.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "agvslam/sim/simulator.h"

namespace agvslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Independent double-precision ray cast against the hall and every static box (no grid, no float).
double brute_force_depth(const Warehouse& w, const Eigen::Vector3d& o, const Eigen::Vector3d& d) {
  double t_best = std::numeric_limits<double>::infinity();
  const Eigen::Vector3d hall(w.width_m, w.depth_m, w.height_m);
  for (int i = 0; i < 3; ++i) {
    if (d[i] > 0) t_best = std::min(t_best, (hall[i] - o[i]) / d[i]);
    if (d[i] < 0) t_best = std::min(t_best, -o[i] / d[i]);
  }
  for (const StaticBox& b : w.boxes) {
    double t_near = -1e300, t_far = 1e300;
    const double lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
    bool miss = false;
    for (int i = 0; i < 3 && !miss; ++i) {
      if (d[i] == 0) {
        if (o[i] < lo[i] || o[i] > hi[i]) miss = true;
        continue;
      }
      double t0 = (lo[i] - o[i]) / d[i], t1 = (hi[i] - o[i]) / d[i];
      if (t0 > t1) std::swap(t0, t1);
      t_near = std::max(t_near, t0);
      t_far = std::min(t_far, t1);
    }
    if (!miss && t_near <= t_far && t_near > 1e-6) t_best = std::min(t_best, t_near);
  }
  return t_best;
}

Simulator make_sim(const std::string& name, uint64_t seed, double scale = 1.0) {
  ScenarioOptions o;
  o.name = name;
  o.seed = seed;
  return Simulator(SimConfig{}.scaled(scale), o);
}

TEST(GroundTruth, DisparityIsFocalTimesBaselineOverRayCastDepth) {
  const Simulator sim = make_sim("static", 21);
  const CameraIntrinsics cam = sim.intrinsics();
  const double bf = sim.config().fx * sim.config().baseline_m;
  for (int frame : {0, 170, 420}) {
    SimFrame f;
    sim.render_frame(frame, f);
    const Eigen::Isometry3d T = sim.T_map_cam(frame);
    int checked = 0, agree = 0;
    for (int v = 3; v < cam.height; v += 13) {
      for (int u = 5; u < cam.width; u += 17) {
        const Eigen::Vector3d d = T.linear() * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
        const double depth = brute_force_depth(sim.warehouse(), T.translation(), d);  // = z: d has unit z
        const double disp_gt = f.disparity_u16.at<uint16_t>(v, u) / 256.0;
        ++checked;
        if (disp_gt > 0 && std::fabs(disp_gt - bf / depth) <= 0.5 / 256 + 1e-4 * disp_gt &&
            std::fabs(f.left_render.depth_m.at<float>(v, u) - depth) <= 1e-4 * depth + 1e-4)
          ++agree;
      }
    }
    // A handful of samples may straddle a box edge where float and double pick different boxes.
    EXPECT_GE(agree, checked - checked / 200) << "frame " << frame << ": " << agree << "/" << checked;
  }
  // A known plane: at frame 0 the camera is level, 0.5 m above the floor, so the bottom-centre pixel sees the
  // floor at depth h * fy / (v - cy).
  SimFrame f0;
  sim.render_frame(0, f0);
  const int v = cam.height - 1, u = static_cast<int>(cam.cx);
  const double z = sim.config().camera_height_m * cam.fy / (v - cam.cy);
  EXPECT_NEAR(f0.disparity_u16.at<uint16_t>(v, u) / 256.0, bf / z, 0.5 / 256 + 1e-9);
  EXPECT_NEAR(f0.left_render.depth_m.at<float>(v, u), z, 1e-5);
  EXPECT_EQ(f0.mask.at<uint8_t>(v, u), 0);
}

TEST(GroundTruth, RasterisedVisibilityEqualsRayCastingEveryPixel) {
  // The renderer finds the static boxes seen at pixel centres by rasterising their faces; the grid ray caster
  // (used for antialiasing samples and by Renderer::cast) must agree with it at every pixel but a few on edges.
  const Simulator sim = make_sim("scene3", 12, 0.5);
  const CameraIntrinsics cam = sim.intrinsics();
  for (int frame : {40, 260}) {
    SimFrame f;
    sim.render_frame(frame, f);
    const Eigen::Isometry3d T = sim.T_map_cam(frame);
    const V3 origin(static_cast<float>(T.translation().x()), static_cast<float>(T.translation().y()),
                    static_cast<float>(T.translation().z()));
    int differ = 0;
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const Eigen::Vector3d d = T.linear() * Eigen::Vector3d((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy, 1.0);
        const RayHit hit = sim.renderer().cast(
            Ray(origin, V3(static_cast<float>(d.x()), static_cast<float>(d.y()), static_cast<float>(d.z()))),
            f.posed_objects);
        const float z = f.left_render.depth_m.at<float>(v, u);
        if (std::fabs(hit.t - z) > 1e-4f * z + 1e-4f) ++differ;
      }
    EXPECT_LT(differ, cam.width * cam.height / 1000) << "frame " << frame;
  }
}

TEST(GroundTruth, PixelsAreShadedRayCastSamplesAndSilhouettesAverageThree) {
  // Every pixel is the shaded pixel-centre ray; silhouette pixels (antialiasing) average it with two more rays
  // at (-0.3, -0.22) and (0.3, 0.22) px. The renderer finds the boxes at all of them by rasterisation; here
  // they are ray cast (the grid DDA), so a few samples that graze a box edge may pick the other surface.
  const Simulator sim = make_sim("scene3", 12, 0.5);
  const CameraIntrinsics cam = sim.intrinsics();
  const float fx = static_cast<float>(cam.fx), fy = static_cast<float>(cam.fy);
  const float cx = static_cast<float>(cam.cx), cy = static_cast<float>(cam.cy);
  const float focal = std::sqrt(fx * fy);
  for (int frame : {40, 260}) {
    SimFrame f;
    sim.render_frame(frame, f);
    const Eigen::Isometry3d T = sim.T_map_cam(frame);
    const Eigen::Matrix3d R = T.linear();
    const V3 origin(static_cast<float>(T.translation().x()), static_cast<float>(T.translation().y()),
                    static_cast<float>(T.translation().z()));
    auto column = [&](int i) {
      return V3(static_cast<float>(R(0, i)), static_cast<float>(R(1, i)), static_cast<float>(R(2, i)));
    };
    const V3 col_x = column(0), col_y = column(1), col_z = column(2);
    auto sample = [&](float u, float v) {
      const Ray ray(origin, col_x * ((u - cx) / fx) + col_y * ((v - cy) / fy) + col_z);
      return sim.renderer().shade(sim.renderer().cast(ray, f.posed_objects), ray, f.posed_objects, focal);
    };
    int edges = 0, edges_agree = 0, plain = 0, plain_agree = 0;
    for (int v = 0; v < cam.height; ++v)
      for (int u = 0; u < cam.width; ++u) {
        const bool edge = f.left_render.edge.at<uint8_t>(v, u) != 0;
        if (!edge && (u + v) % 5 != 0) continue;  // every fifth plain pixel
        const float fu = static_cast<float>(u), fv = static_cast<float>(v);
        float expected = sample(fu, fv);
        if (edge) expected = (expected + sample(fu - 0.3f, fv - 0.22f) + sample(fu + 0.3f, fv + 0.22f)) * (1.0f / 3.0f);
        const bool agree = std::fabs(f.left_render.radiance.at<float>(v, u) - expected) <= 2e-3f;  // 0.6 DN
        (edge ? edges : plain) += 1;
        (edge ? edges_agree : plain_agree) += agree ? 1 : 0;
      }
    EXPECT_GT(edges, 2000) << "frame " << frame;
    EXPECT_GE(edges_agree, edges - edges / 100) << "frame " << frame << ": " << edges_agree << "/" << edges;
    EXPECT_GE(plain_agree, plain - plain / 500) << "frame " << frame << ": " << plain_agree << "/" << plain;
  }
}

TEST(GroundTruth, SgbmOnTheRenderedPairMatchesTheDisparity) {
  for (const char* name : {"static", "scene2"}) {
    const Simulator sim = make_sim(name, 3);
    SimFrame f;
    sim.render_frame(name == std::string("static") ? 90 : 150, f);
    auto sgbm = cv::StereoSGBM::create(0, 64, 5, 8 * 25, 32 * 25, 1, 63, 10, 100, 2, cv::StereoSGBM::MODE_SGBM);
    cv::Mat disp16;
    sgbm->compute(f.left, f.right, disp16);  // CV_16S, disparity * 16
    cv::Mat gt;
    f.disparity_u16.convertTo(gt, CV_32F, 1.0 / 256);
    // Textured pixels away from depth edges.
    cv::Mat gx, gy, grad;
    cv::Sobel(f.left, gx, CV_32F, 1, 0, 3);
    cv::Sobel(f.left, gy, CV_32F, 0, 1, 3);
    cv::magnitude(gx, gy, grad);
    cv::blur(grad, grad, cv::Size(5, 5));
    cv::Mat gt_max, gt_min;
    cv::dilate(gt, gt_max, cv::Mat::ones(7, 7, CV_8U));
    cv::erode(gt, gt_min, cv::Mat::ones(7, 7, CV_8U));
    std::vector<double> errors;
    int candidates = 0;
    for (int v = 0; v < gt.rows; ++v)
      for (int u = 64; u < gt.cols; ++u) {  // SGBM has no disparities in the left 64 columns
        const float d = gt.at<float>(v, u);
        if (d <= 0 || grad.at<float>(v, u) < 40 || gt_max.at<float>(v, u) - gt_min.at<float>(v, u) > 1.0f) continue;
        ++candidates;
        const short s = disp16.at<short>(v, u);
        if (s < 0) continue;
        errors.push_back(std::fabs(s / 16.0 - d));
      }
    ASSERT_GT(candidates, 20000) << name << ": the images must be textured";
    const double valid_ratio = static_cast<double>(errors.size()) / candidates;
    std::sort(errors.begin(), errors.end());
    const double median = errors[errors.size() / 2];
    const double p90 = errors[errors.size() * 9 / 10];
    std::size_t gross = 0;
    for (double e : errors) gross += e > 3.0 ? 1 : 0;
    EXPECT_GT(valid_ratio, 0.75) << name;
    EXPECT_LT(median, 0.35) << name;
    EXPECT_LT(p90, 1.0) << name;
    EXPECT_LT(static_cast<double>(gross) / errors.size(), 0.05) << name;  // occlusions, repetitive racking
    RecordProperty(std::string(name) + "_sgbm_median_abs_err_px", std::to_string(median));
    std::printf(
        "%s: SGBM vs ground truth on %zu textured pixels: valid %.1f %%, median %.3f px, p90 %.3f px, "
        "> 3 px %.2f %%\n",
        name, errors.size(), 100 * valid_ratio, median, p90, 100.0 * gross / errors.size());
  }
}

TEST(GroundTruth, ImagesHaveCornersAllOverForFeatureTrackers) {
  // FAST must find plenty of corners, spread over the image (floor, racks, goods, walls), in each scenario.
  for (const char* name : {"static", "scene1", "scene2", "scene4"}) {
    const Simulator sim = make_sim(name, 4);
    for (int frame : {60, 330}) {
      if (frame >= sim.frame_count()) continue;
      SimFrame f;
      sim.render_frame(frame, f);
      // The threshold (20 grey levels at nominal exposure) follows the sequence's exposure, as the contrast does.
      const int threshold = static_cast<int>(std::lround(20 * sim.exposure_gain(frame)));
      std::vector<cv::KeyPoint> corners;
      cv::FAST(f.left, corners, threshold, true);
      // Fewer where the hall's key light grazes the racks' faces (SimConfig::lighting_variation).
      EXPECT_GT(corners.size(), 1300u) << name << " frame " << frame;
      // Coverage: corners in most cells of an 8 x 6 grid.
      bool cell[6][8] = {};
      for (const auto& kp : corners)
        cell[std::min(5, static_cast<int>(kp.pt.y * 6 / f.left.rows))]
            [std::min(7, static_cast<int>(kp.pt.x * 8 / f.left.cols))] = true;
      int covered = 0;
      for (const auto& row : cell)
        for (bool c : row) covered += c ? 1 : 0;
      EXPECT_GE(covered, 40) << name << " frame " << frame;
      // Mid-grey exposure: neither dark nor saturated.
      const double mean = cv::mean(f.left)[0];
      EXPECT_GT(mean, 60) << name << " frame " << frame;
      EXPECT_LT(mean, 170) << name << " frame " << frame;
      EXPECT_LT(cv::countNonZero(f.left >= 255), static_cast<int>(f.left.total() / 50)) << name;
    }
  }
}

TEST(GroundTruth, LightingAndExposureVaryBetweenSequencesAtTheSameMeanLevel) {
  // Mean lighting of the floor and of walls facing the four horizontal directions.
  const auto mean_lighting = [](const RenderSettings& s) {
    double sum = s.ambient + s.sky + s.sun * std::max(0.0f, s.sun_dir.z);
    for (const V3 n : {V3{1, 0, 0}, V3{-1, 0, 0}, V3{0, 1, 0}, V3{0, -1, 0}})
      sum += s.ambient + s.sun * std::max(0.0f, dot(n, s.sun_dir));
    return sum / 5.0;
  };
  const RenderSettings nominal;
  double exposure_min = 2, exposure_max = 0, sun_z_min = 1, sun_z_max = 0, sun_x_min = 1, sun_x_max = -1;
  for (uint64_t seed = 1; seed <= 12; ++seed) {
    ScenarioOptions o;
    o.name = "static";
    o.seed = seed;
    const Simulator sim(SimConfig{}.scaled(0.25), o);
    const RenderSettings& s = sim.renderer().settings();
    EXPECT_NEAR(mean_lighting(s), mean_lighting(nominal), 1e-4) << "seed " << seed;
    sun_z_min = std::min(sun_z_min, static_cast<double>(s.sun_dir.z));
    sun_z_max = std::max(sun_z_max, static_cast<double>(s.sun_dir.z));
    sun_x_min = std::min(sun_x_min, static_cast<double>(s.sun_dir.x));
    sun_x_max = std::max(sun_x_max, static_cast<double>(s.sun_dir.x));
    exposure_min = std::min(exposure_min, sim.exposure_gain(0));
    exposure_max = std::max(exposure_max, sim.exposure_gain(0));
    // Without the variations: the nominal lighting, and only the smooth +-4 % within a sequence.
    SimConfig fixed = SimConfig{}.scaled(0.25);
    fixed.lighting_variation = 0;
    fixed.exposure_spread = 0;
    const Simulator plain(fixed, o);
    EXPECT_EQ(plain.renderer().settings().sun, nominal.sun);
    EXPECT_EQ(plain.renderer().settings().sun_dir.x, nominal.sun_dir.x);
    EXPECT_NEAR(plain.exposure_gain(0), 1.0, fixed.exposure_variation + 1e-9);
  }
  EXPECT_GT(sun_z_max - sun_z_min, 0.1) << "the key light's elevation varies between halls";
  EXPECT_GT(sun_x_max - sun_x_min, 0.5) << "and its azimuth";
  EXPECT_GT(exposure_max - exposure_min, 0.08) << "the exposure varies between sequences";
  EXPECT_LT(exposure_max, 1.0 + SimConfig{}.exposure_spread + SimConfig{}.exposure_variation + 0.01);
  EXPECT_GT(exposure_min, 1.0 - SimConfig{}.exposure_spread - SimConfig{}.exposure_variation - 0.01);
}

// Checks one frame's mask, id buffer and object list against each other.
void check_mask_consistency(const SimFrame& f, const std::string& what) {
  std::map<int, bool> moving;
  for (const auto& o : f.posed_objects) moving[o.id] = o.moving;
  std::map<int, VisibleObject> seen;
  for (int v = 0; v < f.mask.rows; ++v)
    for (int u = 0; u < f.mask.cols; ++u) {
      const int id = f.left_render.object_id.at<uint16_t>(v, u);
      const bool masked = f.mask.at<uint8_t>(v, u) == 255;
      ASSERT_TRUE(f.mask.at<uint8_t>(v, u) == 0 || masked) << what;
      if (masked) {
        ASSERT_NE(id, 0) << what << ": a masked pixel (" << u << ", " << v << ") shows the static scene";
        ASSERT_TRUE(moving.at(id)) << what << ": a masked pixel belongs to object " << id << ", which stands still";
      } else if (id != 0) {
        ASSERT_FALSE(moving.at(id)) << what << ": a pixel of moving object " << id << " is not masked";
      }
      if (id != 0) {
        VisibleObject& b = seen[id];
        if (b.pixel_count == 0) {
          b.x_min = b.x_max = u;
          b.y_min = b.y_max = v;
        }
        b.x_min = std::min(b.x_min, u);
        b.x_max = std::max(b.x_max, u);
        b.y_min = std::min(b.y_min, v);
        b.y_max = std::max(b.y_max, v);
        ++b.pixel_count;
      }
    }
  ASSERT_EQ(f.objects.size(), seen.size()) << what;
  for (const auto& o : f.objects) {
    const VisibleObject& b = seen.at(o.id);
    EXPECT_EQ(o.pixel_count, b.pixel_count) << what;
    EXPECT_EQ(o.x_min, b.x_min) << what;
    EXPECT_EQ(o.x_max, b.x_max) << what;
    EXPECT_EQ(o.y_min, b.y_min) << what;
    EXPECT_EQ(o.y_max, b.y_max) << what;
    EXPECT_EQ(o.moving, moving.at(o.id)) << what;
  }
}

TEST(GroundTruth, MaskCoversExactlyTheMovingObjects) {
  const Simulator sim = make_sim("scene1", 5, 0.5);
  const int n = sim.frame_count();
  SimFrame f;
  int frames_with_mask = 0, frames_standing_visible = 0;
  for (int k = 0; k < n; k += 8) {
    sim.render_frame(k, f);
    check_mask_consistency(f, "scene1 frame " + std::to_string(k));
    if (HasFatalFailure()) return;
    const int masked = cv::countNonZero(f.mask);
    if (masked > 0) ++frames_with_mask;
    for (const auto& o : f.objects) {
      if (o.id == 1 && o.moving) {
        EXPECT_GT(masked, 0);
      }
      if (o.id == 1 && !o.moving && o.pixel_count > 200) {
        ++frames_standing_visible;
        EXPECT_EQ(masked, 0) << "frame " << k << ": the person stands still, nothing may be masked";
      }
    }
  }
  EXPECT_GE(frames_with_mask, 10);
  EXPECT_GE(frames_standing_visible, 2) << "the person must be seen standing still (present but not moving)";

  // Several people, a forklift that is parked then drives, an AGV that drives then parks.
  for (const char* name : {"scene3", "scene5"}) {
    const Simulator s = make_sim(name, 6, 0.5);
    int moving_vehicle_frames = 0, still_vehicle_frames = 0;
    for (int k = 0; k < s.frame_count(); k += 20) {
      s.render_frame(k, f);
      check_mask_consistency(f, std::string(name) + " frame " + std::to_string(k));
      if (HasFatalFailure()) return;
      for (const auto& o : f.objects)
        if (o.cls != ActorClass::kPerson) (o.moving ? moving_vehicle_frames : still_vehicle_frames)++;
    }
    if (std::string(name) == "scene3") {
      EXPECT_GT(still_vehicle_frames, 0) << "the parked forklift must be visible";
      EXPECT_GT(moving_vehicle_frames, 0) << "the forklift must be seen moving";
    }
  }
}

// Relative pose of frame b from frame a by tracking corners of the left image and PnP with GT-disparity depth.
SE3d relative_pose_from_images(const Simulator& sim, const SimFrame& a, const SimFrame& b, int* inliers_out) {
  const CameraIntrinsics cam = sim.intrinsics();
  const double bf = sim.config().fx * sim.config().baseline_m;
  cv::Mat usable = (a.disparity_u16 > 256 * 2.5) & (a.mask == 0);  // closer than ~22 m, static
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(a.left, corners, 800, 0.01, 7, usable, 3);
  std::vector<cv::Point2f> tracked, back;
  std::vector<uint8_t> status, status_back;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(a.left, b.left, corners, tracked, status, err, cv::Size(21, 21), 3);
  cv::calcOpticalFlowPyrLK(b.left, a.left, tracked, back, status_back, err, cv::Size(21, 21), 3);
  std::vector<cv::Point3f> object;
  std::vector<cv::Point2f> image;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    if (!status[i] || !status_back[i] || cv::norm(back[i] - corners[i]) > 0.5) continue;
    const int u = cvRound(corners[i].x), v = cvRound(corners[i].y);
    const double disp = a.disparity_u16.at<uint16_t>(v, u) / 256.0;
    if (disp <= 0) continue;
    const double z = bf / disp;
    object.emplace_back(static_cast<float>((corners[i].x - cam.cx) * z / cam.fx),
                        static_cast<float>((corners[i].y - cam.cy) * z / cam.fy), static_cast<float>(z));
    image.push_back(tracked[i]);
  }
  const cv::Matx33d K(cam.fx, 0, cam.cx, 0, cam.fy, cam.cy, 0, 0, 1);
  cv::Mat rvec, tvec;
  std::vector<int> inliers;
  if (object.size() < 20 ||
      !cv::solvePnPRansac(object, image, K, cv::noArray(), rvec, tvec, false, 500, 1.0f, 0.999, inliers)) {
    *inliers_out = 0;
    return SE3d::Identity();
  }
  std::vector<cv::Point3f> obj_in;
  std::vector<cv::Point2f> img_in;
  for (int i : inliers) {
    obj_in.push_back(object[static_cast<std::size_t>(i)]);
    img_in.push_back(image[static_cast<std::size_t>(i)]);
  }
  cv::solvePnPRefineLM(obj_in, img_in, K, cv::noArray(), rvec, tvec);
  *inliers_out = static_cast<int>(inliers.size());
  cv::Matx33d R;
  cv::Rodrigues(rvec, R);
  Eigen::Matrix3d Re;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) Re(r, c) = R(r, c);
  return make_se3(Re, Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2)));
}

TEST(GroundTruth, PosesAgreeWithFeatureTrackingAndPnP) {
  const Simulator sim = make_sim("scene4", 8);
  // A straight stretch, the first corner arc (turning ~2.5 deg per frame) and the far side of the loop.
  const std::pair<int, int> pairs[] = {{110, 114}, {168, 171}, {330, 334}, {520, 524}};
  for (const auto& [ka, kb] : pairs) {
    SimFrame a, b;
    sim.render_frame(ka, a);
    sim.render_frame(kb, b);
    int inliers = 0;
    const SE3d T_b_a_images = relative_pose_from_images(sim, a, b, &inliers);
    const SE3d T_b_a_gt = sim.T_w_c(kb).inverse() * sim.T_w_c(ka);
    const SE3d diff = T_b_a_gt.inverse() * T_b_a_images;
    const double t_err = diff.translation().norm();
    const double r_err_deg = rotation_angle_rad(diff) * 180 / kPi;
    EXPECT_GE(inliers, 80) << ka << "->" << kb;
    EXPECT_LT(t_err, 0.02) << ka << "->" << kb << ": motion " << T_b_a_gt.translation().norm() << " m";
    EXPECT_LT(r_err_deg, 0.15) << ka << "->" << kb << ": rotation " << rotation_angle_rad(T_b_a_gt) * 180 / kPi
                               << " deg";
  }
}

}  // namespace
}  // namespace agvslam::sim
