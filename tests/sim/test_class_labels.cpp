// The class labels (class_0): every pixel carries one of the fixed ids, people and vehicles agree with the
// instance image, static goods, racks, floor and walls are where the geometry says.
#include <gtest/gtest.h>

#include <array>
#include <string>

#include "agvslam/sim/semantic_classes.h"
#include "agvslam/sim/simulator.h"
#include "sim_test_util.h"

namespace agvslam::sim {
namespace {

using test::make_sim;

// The class an actor's own pixels may carry besides pallet/box (its goods).
SemanticClass own_class(ActorClass cls) { return actor_part_class(cls, Material::kVehicleBody); }

// Checks one frame; returns the pixel count of each class.
std::array<int, kSemanticClassCount> check_frame(const SimFrame& f, const std::string& what) {
  std::array<int, kSemanticClassCount> counts{};
  EXPECT_EQ(f.classes.type(), CV_8UC1) << what;
  EXPECT_EQ(f.classes.size(), f.left.size()) << what;
  std::vector<int> cls_of_id(256, -1);
  for (const DynamicObject& o : f.posed_objects) cls_of_id[static_cast<std::size_t>(o.id)] = static_cast<int>(o.cls);
  int bad_value = 0, actor_without_class = 0, class_without_actor = 0;
  for (int v = 0; v < f.classes.rows; ++v)
    for (int u = 0; u < f.classes.cols; ++u) {
      const int c = f.classes.at<uint8_t>(v, u);
      const int id = f.instances.at<uint8_t>(v, u);
      if (c >= kSemanticClassCount) {
        ++bad_value;
        continue;
      }
      ++counts[static_cast<std::size_t>(c)];
      const auto sc = static_cast<SemanticClass>(c);
      const bool actor_class =
          sc == SemanticClass::kPerson || sc == SemanticClass::kForklift || sc == SemanticClass::kAgv;
      if (id > 0) {
        // An actor's pixel: its own class, pallet/box where it carries goods, person for a forklift's driver.
        const auto cls = static_cast<ActorClass>(cls_of_id[static_cast<std::size_t>(id)]);
        const bool driver = cls == ActorClass::kForklift && sc == SemanticClass::kPerson;
        if (sc != own_class(cls) && sc != SemanticClass::kPalletBox && !driver) ++actor_without_class;
      } else if (actor_class) {
        ++class_without_actor;  // a person / vehicle class on the static scene
      }
    }
  EXPECT_EQ(bad_value, 0) << what << ": every pixel holds one of the " << kSemanticClassCount << " class ids";
  EXPECT_EQ(actor_without_class, 0) << what << ": actor pixels labelled with another actor class or the scene's";
  EXPECT_EQ(class_without_actor, 0) << what << ": person / vehicle labels outside the actors' instances";
  return counts;
}

TEST(ClassLabels, EveryPixelLabelledAndActorsAgreeWithTheInstances) {
  // scene3: people, a forklift, racks, pallets, floor, walls and the roof down the aisle; scene5: an AGV with its
  // load, people on the loop; crowd: people carrying boxes, a forklift with its driver; pallet: pallets that are
  // actors; follow: a tugger train's carts or a loaded forklift.
  std::array<int, kSemanticClassCount> seen{};
  for (const char* name : {"scene3", "scene5", "crowd", "pallet", "follow"}) {
    const Simulator s = make_sim(name, 3, 0.25);
    SimFrame f;
    for (int k = 0; k < s.frame_count(); k += 25) {
      s.render_frame(k, f, 2);
      const auto counts = check_frame(f, std::string(name) + " frame " + std::to_string(k));
      if (HasFailure()) return;
      for (int i = 0; i < kSemanticClassCount; ++i)
        seen[static_cast<std::size_t>(i)] += counts[static_cast<std::size_t>(i)];
    }
  }
  for (int i = 0; i < kSemanticClassCount; ++i)
    EXPECT_GT(seen[static_cast<std::size_t>(i)], 0)
        << semantic_class_name(static_cast<SemanticClass>(i)) << " never seen";
}

TEST(ClassLabels, StaticLabelsFollowTheGeometry) {
  // Where the depth is that of the floor plane the label is floor; racks and goods are boxes of those materials.
  const Simulator s = make_sim("static", 4, 0.5);
  SimFrame f;
  s.render_frame(0, f);
  const CameraIntrinsics cam = s.intrinsics();
  const Eigen::Isometry3d T = s.T_map_cam(0);
  int floor_ok = 0, floor_wrong = 0;
  for (int v = 0; v < f.classes.rows; ++v)
    for (int u = 0; u < f.classes.cols; ++u) {
      const double z = f.left_render.depth_m.at<float>(v, u);
      if (z <= 0) continue;
      const Eigen::Vector3d p = T * Eigen::Vector3d((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
      const auto c = static_cast<SemanticClass>(f.classes.at<uint8_t>(v, u));
      // On the floor plane (within the float depth's precision; the sides of goods standing on the floor come
      // within a millimetre of it).
      if (p.z() < 2e-5) (c == SemanticClass::kFloor ? floor_ok : floor_wrong)++;
      if (p.z() > s.warehouse().height_m - 1e-3) {
        EXPECT_EQ(c, SemanticClass::kBackground) << u << "," << v;
      }
      if (c == SemanticClass::kFloor) {
        EXPECT_LT(p.z(), 0.02) << u << "," << v;  // floor marks and levellers are flat
      }
    }
  EXPECT_GT(floor_ok, f.classes.total() / 10);
  EXPECT_EQ(floor_wrong, 0);
  // The mapping of the box materials.
  EXPECT_EQ(static_box_class(Material::kRackBeam), SemanticClass::kRack);
  EXPECT_EQ(static_box_class(Material::kShelfDeck), SemanticClass::kRack);
  EXPECT_EQ(static_box_class(Material::kWrappedLoad), SemanticClass::kPalletBox);
  EXPECT_EQ(static_box_class(Material::kPalletStack), SemanticClass::kPalletBox);
  EXPECT_EQ(static_box_class(Material::kPillar), SemanticClass::kWall);
  EXPECT_EQ(actor_part_class(ActorClass::kForklift, Material::kWrappedLoad), SemanticClass::kPalletBox);
  EXPECT_EQ(actor_part_class(ActorClass::kForklift, Material::kTyre), SemanticClass::kForklift);
  EXPECT_EQ(actor_part_class(ActorClass::kForklift, Material::kPersonHead), SemanticClass::kPerson);
  EXPECT_STREQ(semantic_class_name(SemanticClass::kPalletBox), "pallet/box");
}

}  // namespace
}  // namespace agvslam::sim
