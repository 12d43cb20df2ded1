#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <random>

#include "agvslam/io/trajectory_io.h"
#include "io_test_util.h"

namespace agvslam::io {
namespace {
namespace fs = std::filesystem;
using testing::expect_input_error;
using testing::TempDir;

// Poses with large translations (up to ~60 m), arbitrary rotations, and awkward time stamps.
Trajectory random_trajectory(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> rot(-3.0, 3.0), trans(-60.0, 60.0);
  std::uniform_int_distribution<int64_t> jitter(0, 999'999'999);
  Trajectory trajectory;
  int64_t t_ns = 1403715273262142976;
  for (std::size_t i = 0; i < n; ++i) {
    Vector6d xi;
    xi << trans(rng), trans(rng), trans(rng), rot(rng) * 0.5, rot(rng) * 0.5, rot(rng) * 0.5;
    StampedPose pose;
    pose.t_ns = t_ns;
    pose.T_w_c = se3_exp(xi);
    trajectory.push_back(pose);
    t_ns += 50'000'000 + jitter(rng) % 1000;  // not a multiple of a microsecond
  }
  return trajectory;
}

void expect_same_poses(const Trajectory& a, const Trajectory& b, double tol, bool same_times) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (same_times) {
      EXPECT_EQ(a[i].t_ns, b[i].t_ns) << "pose " << i;
    }
    EXPECT_LT((a[i].T_w_c.matrix() - b[i].T_w_c.matrix()).cwiseAbs().maxCoeff(), tol) << "pose " << i;
  }
}

TEST(TrajectoryIo, TumRoundTripKeepsNanosecondsAndPoses) {
  TempDir dir;
  Trajectory trajectory = random_trajectory(200, 1);
  trajectory.push_back({0, SE3d::Identity()});
  trajectory.push_back({-1, SE3d::Identity()});  // negative times survive too
  trajectory.push_back({999'999'999, SE3d::Identity()});
  const std::string path = dir.file("traj_tum.txt");
  write_tum(path, trajectory);
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  const Trajectory back = read_tum(path);
  expect_same_poses(trajectory, back, 1e-9, true);
  EXPECT_EQ(guess_trajectory_format(path), TrajectoryFormat::kTum);
}

TEST(TrajectoryIo, KittiRoundTripWithTimes) {
  TempDir dir;
  const Trajectory trajectory = random_trajectory(200, 2);
  std::vector<int64_t> times_ns;
  for (const auto& p : trajectory) times_ns.push_back(p.t_ns);
  write_kitti_poses(dir.file("poses.txt"), trajectory);
  write_kitti_times(dir.file("times.txt"), times_ns);

  EXPECT_EQ(read_kitti_times(dir.file("times.txt")), times_ns);
  const Trajectory back = read_kitti_poses(dir.file("poses.txt"), &times_ns);
  expect_same_poses(trajectory, back, 1e-9, true);
  const Trajectory via_generic =
      read_trajectory(dir.file("poses.txt"), TrajectoryFormat::kKitti, dir.file("times.txt"));
  expect_same_poses(trajectory, via_generic, 1e-9, true);

  // Without times: 10 Hz from zero.
  const Trajectory untimed = read_kitti_poses(dir.file("poses.txt"));
  ASSERT_EQ(untimed.size(), trajectory.size());
  EXPECT_EQ(untimed[0].t_ns, 0);
  EXPECT_EQ(untimed[3].t_ns, 300'000'000);
  EXPECT_EQ(guess_trajectory_format(dir.file("poses.txt")), TrajectoryFormat::kKitti);
}

TEST(TrajectoryIo, EurocRoundTrip) {
  TempDir dir;
  const Trajectory trajectory = random_trajectory(50, 3);
  write_trajectory(dir.file("gt.csv"), trajectory, TrajectoryFormat::kEuroc);
  EXPECT_EQ(guess_trajectory_format(dir.file("gt.csv")), TrajectoryFormat::kEuroc);
  expect_same_poses(trajectory, read_euroc_csv(dir.file("gt.csv")), 1e-9, true);
}

TEST(TrajectoryIo, TumToleratesCommentsBlankLinesAndCrlf) {
  TempDir dir;
  const std::string path = dir.write("t.txt",
                                     "# comment\r\n\r\n"
                                     "1.5 1 2 3 0 0 0 1\r\n"
                                     "   \n"
                                     "  # indented comment\n"
                                     "1403715273.262142976 -1 0.5 2 0 0 0.7071067811865476 0.7071067811865476\n");
  const Trajectory t = read_tum(path);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_EQ(t[0].t_ns, 1'500'000'000);
  EXPECT_EQ(t[1].t_ns, 1403715273262142976);
  EXPECT_NEAR(t[0].T_w_c.translation().y(), 2.0, 1e-15);
  // 90 degrees about z.
  EXPECT_NEAR(t[1].T_w_c.linear()(1, 0), 1.0, 1e-12);
}

TEST(TrajectoryIo, KittiOrthonormalizesSlightlyOffRotations) {
  TempDir dir;
  // A 30-degree rotation about z printed with 4 digits: off by ~1e-5, well within text precision.
  const std::string path = dir.write("p.txt", "0.8660 -0.5000 0 1\n0.5000 0.8660 0 2\n0 0 1 3\n");
  // Three lines of 4 numbers are not a pose; one line of 12 is.
  expect_input_error([&] { read_kitti_poses(path); }, {path, "line 1", "expected 12 numbers", "found 4"});
  const std::string good = dir.write("q.txt", "0.8660 -0.5000 0 1 0.5000 0.8660 0 2 0 0 1 3\n");
  const Trajectory t = read_kitti_poses(good);
  ASSERT_EQ(t.size(), 1u);
  const Eigen::Matrix3d R = t[0].T_w_c.linear();
  EXPECT_LT((R * R.transpose() - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  EXPECT_NEAR(R(0, 0), 0.8660, 1e-4);
  EXPECT_NEAR(t[0].T_w_c.translation().z(), 3.0, 1e-15);
}

TEST(TrajectoryIo, BadTumFilesNameFileLineAndExpectation) {
  TempDir dir;
  const std::string truncated = dir.write("truncated.txt", "0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 1\n");
  expect_input_error([&] { read_tum(truncated); }, {truncated, "line 2", "expected 8 numbers", "found 7"});

  const std::string word = dir.write("word.txt", "# header\n0.1 0 abc 0 0 0 0 1\n");
  expect_input_error([&] { read_tum(word); }, {word, "line 2", "found 'abc'", "token 3"});

  std::string lines;
  for (int i = 0; i < 6; ++i) lines += std::to_string(i) + " 0 0 0 0 0 0 1\n";
  lines += "6 0 nan 0 0 0 0 1\n";
  const std::string with_nan = dir.write("nan.txt", lines);
  expect_input_error([&] { read_tum(with_nan); }, {with_nan + ": line 7: NaN in pose"});

  const std::string with_inf = dir.write("inf.txt", "0 inf 0 0 0 0 0 1\n");
  expect_input_error([&] { read_tum(with_inf); }, {with_inf, "line 1", "infinite"});

  const std::string zero_q = dir.write("zeroq.txt", "0 0 0 0 0 0 0 0\n");
  expect_input_error([&] { read_tum(zero_q); }, {zero_q, "line 1", "unit quaternion"});

  expect_input_error([&] { read_tum(dir.file("missing.txt")); }, {dir.file("missing.txt"), "file not found"});
}

TEST(TrajectoryIo, BadKittiFilesNameFileLineAndExpectation) {
  TempDir dir;
  const std::string short_line = dir.write("short.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 0 0 1 0 0 0 0 1\n");
  expect_input_error([&] { read_kitti_poses(short_line); }, {short_line, "line 2", "expected 12 numbers", "found 11"});

  const std::string scaled = dir.write("scaled.txt", "2 0 0 0 0 2 0 0 0 0 2 0\n");
  expect_input_error([&] { read_kitti_poses(scaled); }, {scaled, "line 1", "rotation", "det = 8"});

  const std::string reflection = dir.write("reflect.txt", "1 0 0 0 0 1 0 0 0 0 -1 0\n");
  expect_input_error([&] { read_kitti_poses(reflection); }, {reflection, "line 1", "det = -1"});

  const std::string ok = dir.write("ok.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n1 0 0 1 0 1 0 0 0 0 1 0\n");
  const std::vector<int64_t> three_times = {0, 1, 2};
  expect_input_error([&] { read_kitti_poses(ok, &three_times); }, {ok, "expected 3 poses", "found 2"});

  const std::string bad_times = dir.write("times.txt", "0.0\n0.1\nzero\n");
  expect_input_error([&] { read_kitti_times(bad_times); }, {bad_times, "line 3", "found 'zero'"});
  const std::string two_per_line = dir.write("times2.txt", "0.0 0.1\n");
  expect_input_error([&] { read_kitti_times(two_per_line); }, {two_per_line, "line 1", "expected 1 number"});
}

TEST(TrajectoryIo, EurocCsvErrors) {
  TempDir dir;
  const std::string few = dir.write("few.csv", "#t,x,y,z,qw,qx,qy,qz\n1000,0,0,0,1,0,0\n");
  expect_input_error([&] { read_euroc_csv(few); }, {few, "line 2", "expected at least 8", "found 7"});
  const std::string bad_t = dir.write("bad_t.csv", "#t,x,y,z,qw,qx,qy,qz\n1e400,0,0,0,1,0,0,0\n");
  expect_input_error([&] { read_euroc_csv(bad_t); }, {bad_t, "line 2"});
}

TEST(TrajectoryIo, FormatNamesAndGuessing) {
  EXPECT_EQ(parse_trajectory_format("tum"), TrajectoryFormat::kTum);
  EXPECT_EQ(parse_trajectory_format("kitti"), TrajectoryFormat::kKitti);
  EXPECT_EQ(parse_trajectory_format("euroc"), TrajectoryFormat::kEuroc);
  EXPECT_EQ(to_string(TrajectoryFormat::kKitti), "kitti");
  expect_input_error([] { parse_trajectory_format("csv", "--gt-format"); },
                     {"--gt-format", "csv", "expected tum, kitti or euroc"});
  TempDir dir;
  const std::string odd = dir.write("odd.txt", "# only a comment\n1 2 3\n");
  expect_input_error([&] { guess_trajectory_format(odd); }, {odd, "line 2", "found 3"});
  const std::string empty = dir.write("empty.txt", "# nothing\n");
  expect_input_error([&] { guess_trajectory_format(empty); }, {empty, "expected at least one pose line"});
}

TEST(TrajectoryIo, WriteFileAtomicallyReplacesAndNeedsExistingFolder) {
  TempDir dir;
  const std::string path = dir.file("out.txt");
  write_file_atomically(path, "first\n");
  write_file_atomically(path, "second\n");
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text, "second\n");
  EXPECT_FALSE(fs::exists(path + ".tmp"));

  const std::string missing_folder = dir.file("no/such/folder");
  expect_input_error([&] { write_file_atomically(missing_folder + "/out.txt", "x"); },
                     {missing_folder, "does not exist"});
  expect_input_error([&] { write_tum(missing_folder + "/t.txt", {}); }, {missing_folder, "does not exist"});
  EXPECT_FALSE(fs::exists(dir.file("no")));
}

// Real files from shared/.
TEST(TrajectoryIo, ReadsKitti06PosesAndTimes) {
  AGVSLAM_REQUIRE_SHARED(root, "data/kitti06_f000-050");
  const std::vector<int64_t> times_ns = read_kitti_times(root + "/times.txt");
  ASSERT_EQ(times_ns.size(), 51u);
  EXPECT_EQ(times_ns[0], 0);
  EXPECT_EQ(times_ns[1], 104'498'900);
  const Trajectory gt = read_kitti_poses(root + "/poses.txt", &times_ns);
  ASSERT_EQ(gt.size(), 51u);
  EXPECT_LT((gt[0].T_w_c.matrix() - Eigen::Matrix4d::Identity()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_NEAR(gt[1].T_w_c.translation().z(), 1.198998, 1e-9);
  EXPECT_EQ(gt[1].t_ns, 104'498'900);
  EXPECT_EQ(guess_trajectory_format(root + "/poses.txt"), TrajectoryFormat::kKitti);
}

TEST(TrajectoryIo, ReadsOrbSlam3EurocGroundTruthCsv) {
  AGVSLAM_REQUIRE_SHARED(path, "data/euroc_v101_f000-094/gt_orbslam3_left_cam/V101_GT.txt");
  EXPECT_EQ(guess_trajectory_format(path), TrajectoryFormat::kEuroc);
  const Trajectory gt = read_euroc_csv(path);
  // The file covers all of V1_01 (2871 rows); 74 of them fall within the 95 images of the excerpt.
  ASSERT_EQ(gt.size(), 2871u);
  EXPECT_EQ(gt.front().t_ns, 1403715274312143104);  // "1403715274312143104.0000000000", read exactly
  EXPECT_NEAR(gt.front().T_w_c.translation().x(), 0.8687393558, 1e-12);
  EXPECT_NEAR(gt.front().T_w_c.translation().z(), 0.9257726725, 1e-12);
  const int64_t first_image_ns = 1403715273262142976, last_image_ns = 1403715277962142976;
  std::size_t within = 0;
  for (const auto& p : gt) within += (p.t_ns >= first_image_ns && p.t_ns <= last_image_ns) ? 1 : 0;
  EXPECT_EQ(within, 74u);
}

}  // namespace
}  // namespace agvslam::io
