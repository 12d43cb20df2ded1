// People's clothing gives a feature detector corners, as real clothes do (prints, pockets, checks, folds), where
// a plain shirt gives few: FAST corners on a person standing 2 m in front of the AGV's camera.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "agvslam/sim/simulator.h"
#include "sim_test_util.h"

namespace agvslam::sim {
namespace {

struct Corners {
  int on_person = 0;  // FAST corners inside the person's silhouette (not on its outline)
  int person_px = 0;  // pixels of that inner region
};

// Renders `look` standing `distance_m` in front of the camera of `sim`'s first frame, facing it (front) or
// turned away (back), and counts FAST corners (threshold 20 grey levels, ORB's first threshold) inside it.
Corners corners_on_person(const Simulator& sim, double grey_per_radiance, const PersonLook& look, uint32_t seed,
                          bool front, double distance_m = 2.0) {
  const Eigen::Isometry3d T_m_c = sim.T_map_cam(0);
  const Eigen::Vector3d ahead = T_m_c.rotation().col(2);  // optical axis in the map
  const double heading = std::atan2(ahead.y(), ahead.x());
  Actor person;
  person.id = 1;
  person.cls = ActorClass::kPerson;
  person.look = look;
  person.seed = seed;
  ActorState st;
  st.x = T_m_c.translation().x() + distance_m * std::cos(heading);
  st.y = T_m_c.translation().y() + distance_m * std::sin(heading);
  st.yaw_rad = front ? heading + M_PI : heading;
  std::vector<DynamicObject> objects(1);
  pose_actor(person, st, objects[0]);
  CameraRender out;
  sim.renderer().render(sim.intrinsics(), T_m_c, objects, out);
  cv::Mat image;
  out.radiance.convertTo(image, CV_8U, grey_per_radiance);
  cv::Mat inner;
  cv::erode(out.object_id == 1, inner, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(9, 9)));
  std::vector<cv::KeyPoint> keypoints;
  cv::FAST(image, keypoints, 20, true);
  Corners c;
  c.person_px = cv::countNonZero(inner);
  for (const cv::KeyPoint& kp : keypoints)
    c.on_person += inner.at<uint8_t>(cvRound(kp.pt.y), cvRound(kp.pt.x)) != 0 ? 1 : 0;
  return c;
}

TEST(Clothing, PeopleWearClothesWithCornersWhereAPlainShirtHasFew) {
  const Simulator sim = test::make_sim("static", 1, 1.0);
  // The camera's exposure of the first frame: grey level over radiance in the image centre (no vignetting there).
  SimFrame first;
  sim.render_frame(0, first);
  const cv::Rect centre(first.left.cols / 2 - 20, first.left.rows / 2 - 20, 40, 40);
  const double grey_per_radiance = cv::sum(first.left(centre))[0] / cv::sum(first.left_render.radiance(centre))[0];
  // The people of the crowd scenario of a few seeds.
  std::vector<std::pair<PersonLook, uint32_t>> people;
  for (uint64_t seed : {1u, 2u, 3u, 4u}) {
    ScenarioOptions c;
    c.name = "crowd";
    c.seed = seed;
    const Scenario sc = make_scenario(c, generate_warehouse(c.effective_layout_seed()), 20.0);
    for (const Actor& a : sc.actors)
      if (a.cls == ActorClass::kPerson) people.emplace_back(a.look, a.seed);
  }
  ASSERT_GE(people.size(), 20u);
  for (bool front : {true, false}) {
    std::vector<int> dressed;
    int plain_sum = 0;
    for (const auto& [look, seed] : people) {
      // The same person in a plain long-sleeved shirt and plain trousers.
      PersonLook plain;
      plain.height_m = look.height_m;
      plain.skin_shade = look.skin_shade;
      plain.hair_shade = look.hair_shade;
      plain.helmet = look.helmet;
      plain.shirt_shade = look.shirt_shade;
      plain.trousers_shade = look.trousers_shade;
      const Corners p = corners_on_person(sim, grey_per_radiance, plain, seed, front);
      const Corners d = corners_on_person(sim, grey_per_radiance, look, seed, front);
      ASSERT_GT(d.person_px, 5000) << "a person 2 m ahead covers a large part of the view";
      plain_sum += p.on_person;
      dressed.push_back(d.on_person);
    }
    std::sort(dressed.begin(), dressed.end());
    const double plain_mean = static_cast<double>(plain_sum) / people.size();
    const int median = dressed[dressed.size() / 2], low = dressed[dressed.size() / 5];
    std::printf("%s: FAST corners on a plain shirt %.1f on average; dressed: median %d, 20th percentile %d\n",
                front ? "front" : "back", plain_mean, median, low);
    EXPECT_GE(median, 20) << (front ? "front" : "back");
    EXPECT_GE(median, 4 * plain_mean) << (front ? "front" : "back");
    EXPECT_GT(low, plain_mean) << (front ? "front" : "back") << ": most people wear clothes with corners";
  }
}

}  // namespace
}  // namespace agvslam::sim
