// Determinism, the written KITTI layout, and the agvslam-sim tool's command line.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "agvslam/core/error.h"
#include "agvslam/io/calibration_io.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/sim/simulator.h"
#include "common/test_data.h"

namespace agvslam::sim {
namespace {

namespace fs = std::filesystem;

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::stringstream ss(text);
  for (std::string line; std::getline(ss, line);) lines.push_back(line);
  return lines;
}

Simulator make_sim(const std::string& name, uint64_t seed, double scale, int squeeze_to_frames = 0,
                   std::optional<uint64_t> layout_seed = std::nullopt) {
  ScenarioOptions o;
  o.name = name;
  o.seed = seed;
  o.squeeze_to_frames = squeeze_to_frames;
  o.layout_seed = layout_seed;
  return Simulator(SimConfig{}.scaled(scale), o);
}

TEST(Determinism, SameSeedSameBytesAnyThreadCount) {
  const Simulator a = make_sim("scene5", 7, 0.25);
  const Simulator b = make_sim("scene5", 7, 0.25);
  for (int k : {0, 133, 402}) {
    SimFrame fa, fb, fc;
    a.render_frame(k, fa, 1);
    b.render_frame(k, fb, 1);
    a.render_frame(k, fc, 2);
    for (const SimFrame* other : {&fb, &fc}) {
      EXPECT_TRUE(identical(fa.left, other->left)) << "frame " << k;
      EXPECT_TRUE(identical(fa.right, other->right)) << "frame " << k;
      EXPECT_TRUE(identical(fa.disparity_u16, other->disparity_u16)) << "frame " << k;
      EXPECT_TRUE(identical(fa.mask, other->mask)) << "frame " << k;
      EXPECT_EQ(format_objects(k, fa.objects), format_objects(k, other->objects));
    }
    EXPECT_TRUE(fa.T_w_c.isApprox(fb.T_w_c, 0.0));
  }
}

TEST(Determinism, SeedsChangeTheImagesAndLayoutSeedKeepsTheWarehouse) {
  SimFrame f1, f2, f3;
  const Simulator s1 = make_sim("scene2", 1, 0.25);
  const Simulator s2 = make_sim("scene2", 2, 0.25);
  const Simulator s3 = make_sim("scene2", 2, 0.25, 0, 1);  // people/noise of seed 2 in the warehouse of seed 1
  s1.render_frame(0, f1);
  s2.render_frame(0, f2);
  s3.render_frame(0, f3);
  // Different layouts: the depth maps differ a lot; the same layout: identical depth wherever no actor is seen.
  cv::Mat diff12 = cv::abs(f1.left_render.depth_m - f2.left_render.depth_m) > 0.05f;
  EXPECT_GT(cv::countNonZero(diff12), f1.left.total() / 20);
  int differ = 0;
  for (int v = 0; v < f1.left.rows; ++v)
    for (int u = 0; u < f1.left.cols; ++u)
      if (f1.left_render.object_id.at<uint16_t>(v, u) == 0 && f3.left_render.object_id.at<uint16_t>(v, u) == 0 &&
          f1.left_render.depth_m.at<float>(v, u) != f3.left_render.depth_m.at<float>(v, u))
        ++differ;
  EXPECT_EQ(differ, 0);
  // ... but the sensor noise (seeded by --seed) differs.
  EXPECT_FALSE(identical(f1.left, f3.left));
}

TEST(Determinism, NoiseAndExposureAreAsSpecified) {
  // Two renders of the same frame with different seeds but the same layout differ only by noise (and the
  // actors): the difference on static pixels has a standard deviation of ~2 * sqrt(2) grey levels.
  const Simulator a = make_sim("static", 1, 0.5, 0, 42);
  const Simulator b = make_sim("static", 2, 0.5, 0, 42);
  SimFrame fa, fb;
  a.render_frame(5, fa);  // still standing at the start: no vibration, same pose for both seeds
  b.render_frame(5, fb);
  cv::Mat da, db;
  fa.left.convertTo(da, CV_32F);
  fb.left.convertTo(db, CV_32F);
  // Remove the (different) exposure gains before comparing.
  da /= fa.exposure_gain;
  db /= fb.exposure_gain;
  cv::Mat diff = da - db;
  cv::Mat valid = (fa.left > 10) & (fa.left < 245);
  cv::Scalar mean, stddev;
  cv::meanStdDev(diff, mean, stddev, valid);
  EXPECT_NEAR(stddev[0], 2.0 * std::sqrt(2.0), 0.5);
  // The exposure varies smoothly by a few percent, identically for both cameras (same gain per frame).
  double g_min = 10, g_max = 0;
  for (int k = 0; k < a.frame_count(); ++k) {
    const double g = a.exposure_gain(k);
    g_min = std::min(g_min, g);
    g_max = std::max(g_max, g);
    if (k > 0) {
      EXPECT_LT(std::fabs(g - a.exposure_gain(k - 1)), 0.01);
    }
  }
  EXPECT_GT(g_max - g_min, 0.02);
  EXPECT_LT(g_max - g_min, 0.1);
}

TEST(Sequence, WritesTheKittiLayoutReadableAsADataset) {
  const std::string dir = test::make_temp_dir("agvslam-sim-seq");
  const Simulator sim = make_sim("scene3", 4, 0.25, 6);  // the whole timeline in 6 frames: people in view
  write_sequence(sim, dir);
  for (const char* sub : {"image_0", "image_1", "disp_0", "mask_0", "instance_0", "class_0"})
    for (int k = 0; k < 6; ++k) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d.png", k);
      EXPECT_TRUE(fs::is_regular_file(fs::path(dir) / sub / name)) << sub << "/" << name;
    }
  // calib.txt: labelled P0 and P1 with P1[0,3] = -fx * baseline.
  const auto calib_lines = lines_of(read_text(fs::path(dir) / "calib.txt"));
  ASSERT_GE(calib_lines.size(), 2u);
  EXPECT_EQ(calib_lines[0].rfind("P0:", 0), 0u);
  EXPECT_EQ(calib_lines[1].rfind("P1:", 0), 0u);
  std::stringstream p1(calib_lines[1].substr(3));
  std::vector<double> p1v((std::istream_iterator<double>(p1)), std::istream_iterator<double>());
  ASSERT_EQ(p1v.size(), 12u);
  EXPECT_NEAR(p1v[3], -sim.config().fx * 0.12, 1e-9);
  const StereoCalibration calib = io::load_kitti_calib((fs::path(dir) / "calib.txt").string(), cv::Size(188, 120));
  EXPECT_NEAR(calib.baseline_m, 0.12, 1e-9);
  // poses.txt / times.txt
  const auto times = io::read_kitti_times((fs::path(dir) / "times.txt").string());
  ASSERT_EQ(times.size(), 6u);
  EXPECT_EQ(times[1], 50'000'000);
  const Trajectory poses = io::read_kitti_poses((fs::path(dir) / "poses.txt").string(), &times);
  ASSERT_EQ(poses.size(), 6u);
  EXPECT_TRUE(poses[0].T_w_c.isApprox(SE3d::Identity(), 1e-9));
  for (int k = 0; k < 6; ++k) EXPECT_TRUE(poses[static_cast<std::size_t>(k)].T_w_c.isApprox(sim.T_w_c(k), 1e-9));
  // Image formats.
  const cv::Mat disp = cv::imread((fs::path(dir) / "disp_0" / "000003.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat mask = cv::imread((fs::path(dir) / "mask_0" / "000003.png").string(), cv::IMREAD_UNCHANGED);
  const cv::Mat left = cv::imread((fs::path(dir) / "image_0" / "000003.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(disp.type(), CV_16UC1);
  EXPECT_EQ(mask.type(), CV_8UC1);
  EXPECT_EQ(left.type(), CV_8UC1);
  SimFrame f;
  sim.render_frame(3, f);
  EXPECT_TRUE(identical(disp, f.disparity_u16));
  EXPECT_TRUE(identical(mask, f.mask));
  EXPECT_TRUE(identical(left, f.left));
  const cv::Mat classes = cv::imread((fs::path(dir) / "class_0" / "000003.png").string(), cv::IMREAD_UNCHANGED);
  EXPECT_EQ(classes.type(), CV_8UC1);
  EXPECT_TRUE(identical(classes, f.classes));
  // objects.txt: a header comment, then "frame id class moving x_min y_min x_max y_max".
  const auto obj_lines = lines_of(read_text(fs::path(dir) / "objects.txt"));
  ASSERT_FALSE(obj_lines.empty());
  EXPECT_EQ(obj_lines[0].rfind("# frame id class moving x_min y_min x_max y_max", 0), 0u);
  for (std::size_t i = 1; i < obj_lines.size(); ++i) {
    std::stringstream ss(obj_lines[i]);
    int frame, id, moving, x0, y0, x1, y1;
    std::string cls;
    ASSERT_TRUE(static_cast<bool>(ss >> frame >> id >> cls >> moving >> x0 >> y0 >> x1 >> y1)) << obj_lines[i];
    EXPECT_TRUE(cls == "person" || cls == "forklift" || cls == "agv") << cls;
    EXPECT_TRUE(moving == 0 || moving == 1);
    EXPECT_LE(x0, x1);
    EXPECT_LE(y0, y1);
    EXPECT_GE(frame, 0);
    EXPECT_LT(frame, 6);
  }
  // The io module reads it back as a sequence with simulator ground truth.
  io::KittiDataset ds(dir);
  ASSERT_EQ(ds.size(), 6u);
  EXPECT_NEAR(ds.rate_hz(), 20.0, 1e-6);
  EXPECT_NEAR(ds.calibration().baseline_m, 0.12, 1e-9);
  const StereoFrame sf = ds.frame(3);
  EXPECT_TRUE(identical(sf.left, f.left));
  EXPECT_TRUE(identical(sf.right, f.right));
  const auto gt = ds.ground_truth();
  ASSERT_TRUE(gt.has_value());
  EXPECT_EQ(gt->size(), 6u);
  const cv::Mat gt_disp = ds.ground_truth_disparity_px(3);
  ASSERT_FALSE(gt_disp.empty());
  cv::Mat expected;
  f.disparity_u16.convertTo(expected, CV_32F, 1.0 / 256);
  EXPECT_LT(cv::norm(gt_disp, expected, cv::NORM_INF), 1e-4);
  const cv::Mat gt_mask = ds.ground_truth_mask(3);
  ASSERT_FALSE(gt_mask.empty());
  EXPECT_EQ(cv::countNonZero(gt_mask != f.mask), 0);
  // instance_0: each pixel's actor id; every object's pixels lie inside its objects.txt box, the moving ones make
  // up the motion mask exactly, and the box of an object's own pixels is its box.
  const cv::Mat gt_instances = ds.ground_truth_instances(3);
  ASSERT_FALSE(gt_instances.empty());
  EXPECT_EQ(gt_instances.type(), CV_8UC1);
  EXPECT_TRUE(identical(gt_instances, f.instances));
  ASSERT_FALSE(f.objects.empty());
  cv::Mat moving_from_instances = cv::Mat::zeros(gt_instances.size(), CV_8UC1);
  for (const auto& o : f.objects) {
    const cv::Mat own = gt_instances == o.id;
    EXPECT_EQ(cv::countNonZero(own), o.pixel_count) << "object " << o.id;
    const cv::Rect box = cv::boundingRect(own);
    EXPECT_EQ(box, cv::Rect(cv::Point(o.x_min, o.y_min), cv::Point(o.x_max + 1, o.y_max + 1))) << "object " << o.id;
    if (o.moving) moving_from_instances.setTo(255, own);
  }
  EXPECT_EQ(cv::countNonZero(moving_from_instances != gt_mask), 0);
  fs::remove_all(dir);
}

TEST(Sequence, OutputFolderProblemsRaiseInputErrorNamingTheOption) {
  const std::string dir = test::make_temp_dir("agvslam-sim-bad");
  const std::string file = (fs::path(dir) / "a_file").string();
  std::ofstream(file) << "x";
  try {
    prepare_output_dir(file);
    FAIL() << "a file is not a folder";
  } catch (const InputError& e) {
    EXPECT_EQ(e.source(), "--out");
    EXPECT_EQ(e.where(), file);
  }
  EXPECT_THROW(prepare_output_dir((fs::path(file) / "below").string()), InputError);
  EXPECT_THROW(prepare_output_dir("/proc/agvslam-sim-cannot-write-here"), InputError);
  fs::remove_all(dir);
}

class Tool : public ::testing::Test {
 protected:
  void SetUp() override {
    tool_ = test::tool_path("agvslam-sim");
    if (!fs::exists(tool_)) GTEST_SKIP() << tool_ << " is not built";
    dir_ = test::make_temp_dir("agvslam-sim-tool");
    params_ = (fs::path(dir_) / "small.yaml").string();
    std::ofstream(params_) << "camera:\n  width: 188\n  height: 120\n  fx: 115\nsensor:\n  noise_sigma_dn: 2\n";
  }
  void TearDown() override {
    if (!dir_.empty()) fs::remove_all(dir_);
  }
  int run(const std::string& args, std::string* output) { return test::run_command("'" + tool_ + "' " + args, output); }
  std::string tool_, dir_, params_;
};

TEST_F(Tool, RejectsBadArgumentsWithAClearMessage) {
  std::string out;
  EXPECT_EQ(run("--scenario scene9 --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("--scenario"), std::string::npos) << out;
  EXPECT_NE(out.find("scene1"), std::string::npos) << out;

  EXPECT_EQ(run("--scenario scene1 --frames 0 --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("--frames"), std::string::npos) << out;
  EXPECT_EQ(run("--scenario scene1 --frames -5 --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("--frames"), std::string::npos) << out;

  EXPECT_EQ(run("--scenario scene1 --squeeze-to 0 --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("--squeeze-to"), std::string::npos) << out;
  // --frames cuts the timeline: more frames than it has (400 for scene1) is an error that names the way out.
  EXPECT_EQ(run("--scenario scene1 --frames 401 --params " + params_ + " --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("--frames"), std::string::npos) << out;
  EXPECT_NE(out.find("at most 400"), std::string::npos) << out;
  EXPECT_NE(out.find("--squeeze-to"), std::string::npos) << out;

  EXPECT_EQ(run("--scenario scene1 --out /proc/agvslam-sim-out", &out), 2);
  EXPECT_NE(out.find("--out"), std::string::npos) << out;
  EXPECT_NE(out.find("/proc/agvslam-sim-out"), std::string::npos) << out;

  EXPECT_EQ(run("--scenario scene2 --start-offset 9 --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("--start-offset"), std::string::npos) << out;

  EXPECT_EQ(run("--scenario scene2 --params /nonexistent/sim.yaml --out " + dir_ + "/x", &out), 2);
  EXPECT_NE(out.find("/nonexistent/sim.yaml"), std::string::npos) << out;
}

TEST_F(Tool, FramesCutsTheTimelineAndSqueezeToPlaysItOverFewerFrames) {
  std::string out;
  ASSERT_EQ(run("--scenario scene2 --frames 6 --seed 3 --params " + params_ + " --out " + dir_ + "/cut", &out), 0)
      << out;
  ASSERT_EQ(
      run("--scenario scene2 --squeeze-to 40 --frames 6 --seed 3 --params " + params_ + " --out " + dir_ + "/fast",
          &out),
      0)
      << out;
  const auto cut = lines_of(read_text(fs::path(dir_) / "cut" / "poses.txt"));
  const auto fast = lines_of(read_text(fs::path(dir_) / "fast" / "poses.txt"));
  ASSERT_EQ(cut.size(), 6u);
  ASSERT_EQ(fast.size(), 6u);
  const std::string cut_json = read_text(fs::path(dir_) / "cut" / "scenario.json");
  const std::string fast_json = read_text(fs::path(dir_) / "fast" / "scenario.json");
  EXPECT_NE(cut_json.find("\"timeline_frames\": 400"), std::string::npos) << cut_json;
  EXPECT_NE(cut_json.find("\"speed_factor\": 1.0"), std::string::npos) << cut_json;
  EXPECT_NE(fast_json.find("\"timeline_frames\": 40"), std::string::npos) << fast_json;
  EXPECT_NE(fast_json.find("\"speed_factor\": 10.0"), std::string::npos) << fast_json;
  // The class ids of class_0 are listed.
  EXPECT_NE(cut_json.find("\"name\": \"pallet/box\""), std::string::npos) << cut_json;
  // Frame 0 is the identity in both; by frame 5 the squeezed run (ten times as fast) has driven further.
  EXPECT_EQ(cut[0], fast[0]);
  auto z_of = [](const std::string& line) {
    std::istringstream in(line);
    double v[12];
    for (double& x : v) in >> x;
    return v[11];
  };
  EXPECT_GT(z_of(fast[5]), z_of(cut[5]) + 1e-3);
}

TEST_F(Tool, WritesTheSameSequenceWithOneOrTwoThreads) {
  std::string out1, out2;
  ASSERT_EQ(run("--scenario scene5 --squeeze-to 4 --seed 9 --params " + params_ + " --out " + dir_ + "/t1", &out1), 0)
      << out1;
  ASSERT_EQ(run("--scenario scene5 --squeeze-to 4 --seed 9 --threads 2 --params " + params_ + " --out " + dir_ + "/t2",
                &out2),
            0)
      << out2;
  EXPECT_NE(out1.find("AGV speed"), std::string::npos) << out1;
  EXPECT_NE(out1.find("baseline_m=0.12,"), std::string::npos) << "the settings are echoed at start-up:\n" << out1;
  for (const char* file :
       {"calib.txt", "times.txt", "poses.txt", "objects.txt", "image_0/000003.png", "image_1/000003.png",
        "disp_0/000003.png", "mask_0/000003.png", "instance_0/000003.png", "class_0/000003.png"}) {
    const std::string a = read_text(fs::path(dir_) / "t1" / file), b = read_text(fs::path(dir_) / "t2" / file);
    EXPECT_FALSE(a.empty()) << file;
    EXPECT_EQ(a, b) << file << " differs between --threads 1 and 2";
  }
}

}  // namespace
}  // namespace agvslam::sim
