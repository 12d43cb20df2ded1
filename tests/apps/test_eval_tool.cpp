// Runs agvslam-eval on trajectory files written here as text, and on the real KITTI 06 ground truth.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>
#include <sstream>

#include "agvslam/core/se3.h"
#include "common/test_data.h"

namespace agvslam {
namespace {
namespace fs = std::filesystem;

struct Pose {
  double t_s;
  SE3d T;
};

std::vector<Pose> make_path(int n) {
  std::vector<Pose> out;
  double yaw = 0;
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    out.push_back({i * 0.1, make_se3(Eigen::Matrix3d(Eigen::AngleAxisd(yaw, -Eigen::Vector3d::UnitY())), p)});
    yaw += 0.01 * std::sin(i * 0.05);
    p += 0.5 * Eigen::Vector3d(std::sin(yaw), 0, std::cos(yaw));
  }
  return out;
}

void write_kitti(const std::string& path, const std::vector<Pose>& poses) {
  std::ofstream f(path);
  f.precision(12);
  for (const auto& p : poses) {
    const Eigen::Matrix4d m = p.T.matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) f << m(r, c) << (r == 2 && c == 3 ? "\n" : " ");
  }
}

void write_times(const std::string& path, const std::vector<Pose>& poses) {
  std::ofstream f(path);
  f.precision(12);
  for (const auto& p : poses) f << p.t_s << "\n";
}

void write_tum(const std::string& path, const std::vector<Pose>& poses) {
  std::ofstream f(path);
  f << "# timestamp tx ty tz qx qy qz qw\n";
  f.precision(12);
  for (const auto& p : poses) {
    const Eigen::Quaterniond q(p.T.linear());
    const Eigen::Vector3d t = p.T.translation();
    f << p.t_s << " " << t.x() << " " << t.y() << " " << t.z() << " " << q.x() << " " << q.y() << " " << q.z() << " "
      << q.w() << "\n";
  }
}

std::string first_line(const std::string& s) { return s.substr(0, s.find('\n')); }

double ate_from_output(const std::string& out) {
  const std::string line = first_line(out);
  EXPECT_EQ(line.rfind("ATE_RMSE_M ", 0), 0u) << "first line was: " << line;
  return std::stod(line.substr(11));
}

class EvalTool : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = test::make_temp_dir("agvslam-eval-test"); }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }
  std::string path(const std::string& name) const { return (fs::path(dir_) / name).string(); }
  int eval(const std::string& args, std::string* out) {
    return test::run_command(test::tool_path("agvslam-eval") + " " + args, out);
  }
  std::string dir_;
};

TEST_F(EvalTool, RigidOffsetGivesZeroAteAfterSe3Alignment) {
  const auto gt = make_path(200);
  auto est = gt;
  const SE3d T_offset = se3_exp((Vector6d() << 4, -2, 9, 0.2, 1.0, -0.3).finished());
  for (auto& p : est) p.T = T_offset * p.T;
  write_kitti(path("gt.txt"), gt);
  write_times(path("times.txt"), gt);
  write_tum(path("est.tum"), est);
  std::string out;
  ASSERT_EQ(eval("--gt " + path("gt.txt") + " --gt-format kitti --est " + path("est.tum") +
                     " --est-format tum --times " + path("times.txt") + " --align se3",
                 &out),
            0)
      << out;
  EXPECT_LT(ate_from_output(out), 1e-6) << out;
  EXPECT_NE(out.find("by time stamp"), std::string::npos) << out;
  // Without alignment the offset shows in full.
  ASSERT_EQ(
      eval("--gt " + path("gt.txt") + " --est " + path("est.tum") + " --times " + path("times.txt") + " --align none",
           &out),
      0)
      << out;
  EXPECT_GT(ate_from_output(out), 1.0);
}

TEST_F(EvalTool, NoiseOfKnownSizeGivesExpectedRmseAndJsonAndPlot) {
  const auto gt = make_path(3000);
  auto est = gt;
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 0.02);
  for (auto& p : est) p.T.translation() += Eigen::Vector3d(n(rng), n(rng), n(rng));
  write_kitti(path("gt.txt"), gt);
  write_kitti(path("est.txt"), est);
  std::string out;
  ASSERT_EQ(eval("--gt " + path("gt.txt") + " --est " + path("est.txt") + " --json " + path("r.json") + " --plot " +
                     path("top.png"),
                 &out),
            0)
      << out;
  const double ate = ate_from_output(out);
  EXPECT_NEAR(ate, 0.02 * std::sqrt(3.0), 0.002) << out;
  EXPECT_NE(out.find("by index"), std::string::npos);
  EXPECT_NE(out.find("KITTI: t_rel"), std::string::npos) << "a 1.5 km path must get KITTI segment errors";

  std::ifstream jf(path("r.json"));
  ASSERT_TRUE(jf.good());
  const nlohmann::json j = nlohmann::json::parse(jf);
  EXPECT_NEAR(j["ate_m"]["rmse"].get<double>(), ate, 1e-6);
  EXPECT_EQ(j["associated"].get<int>(), 3000);
  EXPECT_TRUE(j["kitti"].is_object());
  EXPECT_EQ(j["kitti"]["segments"].size(), 8u);

  const cv::Mat png = cv::imread(path("top.png"));
  ASSERT_FALSE(png.empty());
  EXPECT_EQ(png.cols, 1000);
}

TEST_F(EvalTool, BadInputNamesTheFileLineOrOption) {
  const auto gt = make_path(20);
  write_kitti(path("gt.txt"), gt);
  write_tum(path("est.tum"), gt);
  std::string out;

  EXPECT_EQ(eval("--gt " + path("missing.txt") + " --est " + path("est.tum"), &out), 2);
  EXPECT_NE(out.find("missing.txt"), std::string::npos) << out;

  EXPECT_EQ(eval("--gt " + path("gt.txt") + " --est " + path("est.tum") + " --gt-format kitti --est-format tum", &out),
            2);
  EXPECT_NE(out.find("--times"), std::string::npos) << out;

  write_times(path("times.txt"), gt);
  EXPECT_EQ(
      eval("--gt " + path("gt.txt") + " --est " + path("est.tum") + " --align affine --times " + path("times.txt"),
           &out),
      2);
  EXPECT_NE(out.find("--align"), std::string::npos) << out;

  {
    std::ofstream f(path("nan.tum"));
    f << "0.0 0 0 0 0 0 0 1\n0.1 nan 0 0 0 0 0 1\n";
  }
  EXPECT_EQ(eval("--gt " + path("nan.tum") + " --est " + path("est.tum"), &out), 2);
  EXPECT_NE(out.find("nan.tum"), std::string::npos) << out;
  EXPECT_NE(out.find("line 2"), std::string::npos) << out;

  {
    std::ofstream f(path("short.txt"));
    f << "1 0 0 0 0 1 0 0 0 0 1\n";
  }
  EXPECT_EQ(eval("--gt " + path("short.txt") + " --gt-format kitti --est " + path("gt.txt"), &out), 2);
  EXPECT_NE(out.find("short.txt"), std::string::npos) << out;
  EXPECT_NE(out.find("line 1"), std::string::npos) << out;

  EXPECT_EQ(eval("--gt " + path("gt.txt") + " --est " + path("est.tum") + " --gt-format xyz", &out), 2);
  EXPECT_NE(out.find("--gt-format"), std::string::npos) << out;
}

TEST_F(EvalTool, OdometryCheckReportsAScaleErrorAndAFrozenStretch) {
  const auto truth = make_path(400);  // 0.5 m per 0.1 s
  write_tum(path("odometry.tum"), truth);
  {  // The same motion as a controller's speed / yaw-rate CSV.
    std::ofstream f(path("odometry.csv"));
    f << "t_s,speed_mps,yaw_rate_radps\n";
    f.precision(12);
    for (std::size_t i = 0; i < truth.size(); ++i) {
      const std::size_t k = std::min(i, truth.size() - 2);
      const double yaw0 = std::atan2(-truth[k].T.linear()(2, 0), truth[k].T.linear()(0, 0));
      const double yaw1 = std::atan2(-truth[k + 1].T.linear()(2, 0), truth[k + 1].T.linear()(0, 0));
      f << truth[i].t_s << "," << 5.0 << "," << (yaw1 - yaw0) / 0.1 << "\n";
    }
  }
  auto scaled = truth;
  for (auto& p : scaled) p.T.translation() *= 1.05;
  write_tum(path("scaled.tum"), scaled);
  auto frozen = truth;
  for (std::size_t i = 201; i < 215; ++i) frozen[i].T = frozen[200].T;
  write_tum(path("frozen.tum"), frozen);

  std::string out;
  ASSERT_EQ(
      eval("--est " + path("scaled.tum") + " --odometry " + path("odometry.tum") + " --json " + path("o.json"), &out),
      0)
      << out;
  EXPECT_EQ(first_line(out).rfind("ODOMETRY_DISTANCE_RATIO 1.05", 0), 0u) << out;
  EXPECT_NE(out.find("OUTSIDE the 3 % tolerance"), std::string::npos) << out;
  const nlohmann::json j = nlohmann::json::parse(std::ifstream(path("o.json")));
  EXPECT_NEAR(j["odometry"]["distance_ratio"].get<double>(), 1.05, 1e-3);
  EXPECT_FALSE(j["odometry"]["distance_within_tolerance"].get<bool>());

  ASSERT_EQ(eval("--est " + path("frozen.tum") + " --odometry " + path("odometry.csv"), &out), 0) << out;
  EXPECT_NE(out.find("speed / yaw rate"), std::string::npos) << out;
  EXPECT_NE(out.find("frames 200-2"), std::string::npos) << out;  // the frozen stretch is listed

  // With ground truth as well: the ATE line comes first.
  write_times(path("times.txt"), truth);
  write_kitti(path("gt.txt"), truth);
  ASSERT_EQ(eval("--gt " + path("gt.txt") + " --times " + path("times.txt") + " --est " + path("odometry.tum") +
                     " --odometry " + path("odometry.tum"),
                 &out),
            0)
      << out;
  EXPECT_LT(ate_from_output(out), 1e-9);
  EXPECT_NE(out.find("ratio 1.0000 (within"), std::string::npos) << out;

  EXPECT_EQ(eval("--est " + path("frozen.tum"), &out), 2);
  EXPECT_NE(out.find("--odometry"), std::string::npos) << out;
  EXPECT_EQ(eval("--est " + path("frozen.tum") + " --odometry " + path("odometry.csv") + " --est-axes ros", &out), 2);
  EXPECT_NE(out.find("--est-axes"), std::string::npos) << out;
}

TEST_F(EvalTool, RealKittiGroundTruthAgainstItself) {
  AGVSLAM_REQUIRE_SHARED(kitti, "data/kitti06_f000-050");
  std::string out;
  ASSERT_EQ(
      eval("--gt " + kitti + "/poses.txt --est " + kitti + "/poses.txt --gt-format kitti --est-format kitti", &out), 0)
      << out;
  EXPECT_LT(ate_from_output(out), 1e-9);
  EXPECT_NE(out.find("51 associated"), std::string::npos) << out;
}

}  // namespace
}  // namespace agvslam
