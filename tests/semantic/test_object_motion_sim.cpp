// The per-object motion test with the geometric detector's points on the simulator (scene1: a person walks in
// front of the stationary AGV, stands, walks back). The segmentation is the ground truth, so this scores the
// motion test alone: the walking person must be found moving, the standing one must keep its features.
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/imgproc.hpp>

#include "agvslam/dynamic/detector.h"
#include "agvslam/semantic/object_motion.h"
#include "sim_sequence.h"

namespace agvslam::semantic {
namespace {

// Whether the scenario's person moves at frame i, and whether it is inside the view (its centre 80 px from the
// edges) 1-6 m ahead.
struct PersonAt {
  bool moving = false, in_view = false;
};
PersonAt person_at(const sim::Simulator& simulator, int i) {
  std::vector<sim::DynamicObject> objects;
  simulator.pose_objects(i, objects);
  const Eigen::Isometry3d T_cam_map = simulator.T_map_cam(i).inverse();
  const PinholeCamera cam = simulator.calibration().left;
  for (const sim::DynamicObject& o : objects) {
    if (o.cls != sim::ActorClass::kPerson) continue;
    const Eigen::Vector3d p = T_cam_map * Eigen::Vector3d(o.origin.x, o.origin.y, o.origin.z);
    const double u = cam.fx * p.x() / p.z() + cam.cx;
    return {o.moving, p.z() > 1.0 && p.z() < 6.0 && u > 80 && u < cam.width - 80};
  }
  return {};
}

// Runs the detector and the motion test over frames first..last; returns the fraction of frames from
// first + settle on in which the person was judged moving.
double moving_fraction(test::SimSequence& seq, int first, int last, int settle) {
  dynamic::DynamicDetector detector(seq.simulator().calibration());
  const ObjectMotionTest motion{MotionConfig{}};
  std::vector<SemanticObject> person(1);
  dynamic::DetectorResult result;
  int judged = 0, moving = 0;
  for (int i = first; i <= last; ++i) {
    const sim::SimFrame& f = seq.frame(i);
    StereoFrame frame;
    frame.index = static_cast<std::size_t>(i);
    frame.t_ns = f.t_ns;
    frame.left = f.left;
    frame.right = f.right;
    detector.detect(frame, result);
    person[0].mask = seq.labels(i) == 5;
    person[0].box = cv::boundingRect(person[0].mask);
    const std::vector<MotionVote> votes = motion.update(result.points, &result.ground_plane, person);
    if (i >= first + settle) {
      ++judged;
      moving += person[0].moving ? 1 : 0;
    }
    std::printf("frame %d: %d tested points, %d moving, evidence %.2f -> %s\n", i, votes[0].tested_points,
                votes[0].moving_points, person[0].evidence, person[0].moving ? "moving" : "standing");
  }
  return judged ? static_cast<double>(moving) / judged : -1;
}

TEST(ObjectMotionSim, WalkingPersonMovesStandingPersonDoesNot) {
  test::SimSequence seq("scene1");
  const sim::Simulator& simulator = seq.simulator();
  int walk = -1, stand = -1;
  for (int i = 1; i + 40 < simulator.frame_count(); ++i) {
    const PersonAt p = person_at(simulator, i);
    if (walk < 0 && p.moving && p.in_view && person_at(simulator, i + 15).moving) walk = i;
    if (walk >= 0 && stand < 0 && !p.moving && p.in_view) {
      bool still = true;
      for (int k = 1; k <= 40 && still; ++k) still = !person_at(simulator, i + k).moving;
      if (still) stand = i;
    }
  }
  ASSERT_GT(walk, 0) << "scene1's person should walk in view";
  ASSERT_GT(stand, walk) << "scene1's person should stand in view for 40 frames";
  const double walking = moving_fraction(seq, walk, walk + 15, 3);
  // A run of its own from `stand` on (how the evidence of a walk decays is tested in test_object_motion.cpp).
  const double standing = moving_fraction(seq, stand, stand + 30, 3);
  std::printf("walking frames %d..%d: moving in %.2f; standing frames %d..%d: moving in %.2f\n", walk + 3, walk + 15,
              walking, stand + 3, stand + 30, standing);
  EXPECT_GE(walking, 0.8);
  EXPECT_LE(standing, 0.1);
}

}  // namespace
}  // namespace agvslam::semantic
