// agvslam-eval: compares an estimated trajectory with ground truth, with the vehicle's wheel odometry, or both.
//
//   agvslam-eval --est FILE (--gt FILE | --odometry FILE) [--gt-format kitti|tum|euroc] [--est-format ...]
//                [--times FILE] [--align se3|sim3|none] [--max-dt-ms MS] [--json OUT] [--plot OUT.png]
//                [--odometry-format tum|euroc|csv] [--est-axes camera|base] [--odometry-axes camera|base]
//                [--odometry-window-s S] [--odometry-disagreement R] [--odometry-tolerance R]
//
// Ground truth: association is by index when both files are KITTI poses without times; otherwise by nearest time
// stamp (--times gives KITTI files their time stamps). The first line of stdout is `ATE_RMSE_M <value>`.
// Odometry (a vehicle without ground truth): the trajectory's distance, speed and heading against wheel odometry
// given as poses (TUM / EuRoC) or as a CSV of t_s, speed_mps, yaw_rate_radps (eval/odometry_check.h); without --gt
// the first line is `ODOMETRY_DISTANCE_RATIO <value>`.
// Exit status: 0 on success, 2 on bad input (with a message naming the file or option), 1 on any other failure.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>

#include "agvslam/core/error.h"
#include "agvslam/eval/metrics.h"
#include "agvslam/eval/odometry_check.h"
#include "agvslam/eval/plot.h"
#include "agvslam/io/odometry_io.h"
#include "agvslam/io/trajectory_io.h"
#include "tool_main.h"

namespace {

using agvslam::InputError;
using agvslam::io::TrajectoryFormat;
namespace eval = agvslam::eval;

nlohmann::json to_json(const eval::ErrorStats& s) {
  return {{"count", s.count}, {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median},
          {"std", s.std},     {"min", s.min},   {"max", s.max}};
}

struct Options {
  std::string gt_path, est_path, gt_format, est_format, times_path, align = "se3", json_path, plot_path;
  double max_dt_ms = 20.0;
  int rpe_delta = 1;
  std::string odometry_path, odometry_format, est_axes = "camera", odometry_axes = "camera";
  eval::OdometryCheckConfig odometry;
};

agvslam::Trajectory load(const std::string& path, const std::string& format_name, const std::string& option,
                         const std::string& times_path, TrajectoryFormat* format_out) {
  const TrajectoryFormat format = format_name.empty() ? agvslam::io::guess_trajectory_format(path)
                                                      : agvslam::io::parse_trajectory_format(format_name, option);
  *format_out = format;
  std::optional<std::string> times;
  if (format == TrajectoryFormat::kKitti && !times_path.empty()) times = times_path;
  return agvslam::io::read_trajectory(path, format, times);
}

// The ATE / RPE / KITTI figures against ground truth (stdout, and into `j`).
void compare_with_ground_truth(const Options& o, eval::AlignMode align, const agvslam::Trajectory& est,
                               TrajectoryFormat est_format, nlohmann::json& j) {
  TrajectoryFormat gt_format{};
  const agvslam::Trajectory gt = load(o.gt_path, o.gt_format, "--gt-format", o.times_path, &gt_format);
  if (gt.empty()) throw InputError(o.gt_path, "", "expected at least one pose, found none");

  const bool by_index =
      gt_format == TrajectoryFormat::kKitti && est_format == TrajectoryFormat::kKitti && o.times_path.empty();
  if (!by_index && o.times_path.empty() &&
      (gt_format == TrajectoryFormat::kKitti || est_format == TrajectoryFormat::kKitti))
    throw InputError("--times", "",
                     "a KITTI pose file has no time stamps: give --times times.txt to associate it "
                     "with a time-stamped (TUM/EuRoC) trajectory");
  const eval::PosePairs pairs = by_index
                                    ? eval::associate_by_index(gt, est)
                                    : eval::associate_by_timestamp(gt, est, static_cast<int64_t>(o.max_dt_ms * 1e6));
  if (pairs.size() < 2)
    throw InputError(o.est_path, "association",
                     "expected at least 2 poses matching the ground truth " +
                         std::string(by_index ? "by index" : "within --max-dt-ms of a time stamp") + ", found " +
                         std::to_string(pairs.size()));

  const eval::AteResult ate = eval::compute_ate(pairs, align);
  const double scale = align == eval::AlignMode::kSim3 ? ate.alignment.scale : 1.0;
  const eval::RpeResult rpe = eval::compute_rpe(pairs, o.rpe_delta, scale);
  const std::optional<eval::KittiResult> kitti = eval::compute_kitti_relative(pairs, scale);
  const double gt_length = eval::path_length_m(pairs.T_w_c_gt);

  std::printf("ATE_RMSE_M %.6f\n", ate.translation_m.rmse);
  std::printf("poses: %zu associated (%s) of %zu estimated, %zu ground truth; ground-truth path %.3f m\n", pairs.size(),
              by_index ? "by index" : "by time stamp", est.size(), gt.size(), gt_length);
  std::printf("alignment: %s", eval::to_string(align).c_str());
  if (align == eval::AlignMode::kSim3) std::printf(" (scale %.6f)", ate.alignment.scale);
  std::printf("\n");
  const auto& a = ate.translation_m;
  std::printf("ATE [m]:       rmse %.6f  mean %.6f  median %.6f  std %.6f  max %.6f\n", a.rmse, a.mean, a.median, a.std,
              a.max);
  std::printf("RPE/%d [m]:     rmse %.6f  mean %.6f  median %.6f  std %.6f  max %.6f\n", rpe.delta_frames,
              rpe.translation_m.rmse, rpe.translation_m.mean, rpe.translation_m.median, rpe.translation_m.std,
              rpe.translation_m.max);
  std::printf("RPE/%d [deg]:   rmse %.6f  mean %.6f  median %.6f  std %.6f  max %.6f\n", rpe.delta_frames,
              rpe.rotation_deg.rmse, rpe.rotation_deg.mean, rpe.rotation_deg.median, rpe.rotation_deg.std,
              rpe.rotation_deg.max);
  if (kitti) {
    std::printf("KITTI: t_rel %.4f %%  r_rel %.4f deg/100m  (%zu sub-sequences)\n", kitti->t_rel_pct,
                kitti->r_rel_deg_per_100m, kitti->count);
  } else {
    std::printf("KITTI: t_rel/r_rel not computed (ground-truth path %.1f m is shorter than 100 m)\n", gt_length);
  }

  {
    j["gt"] = o.gt_path;
    j["est"] = o.est_path;
    j["associated"] = pairs.size();
    j["association"] = by_index ? "index" : "timestamp";
    j["align"] = eval::to_string(align);
    j["scale"] = ate.alignment.scale;
    j["gt_path_length_m"] = gt_length;
    j["ate_m"] = to_json(ate.translation_m);
    j["rpe"] = {{"delta_frames", rpe.delta_frames},
                {"translation_m", to_json(rpe.translation_m)},
                {"rotation_deg", to_json(rpe.rotation_deg)}};
    if (kitti) {
      nlohmann::json segs = nlohmann::json::array();
      for (const auto& s : kitti->per_length)
        segs.push_back({{"length_m", s.length_m},
                        {"count", s.count},
                        {"t_rel_pct", s.t_rel_pct},
                        {"r_rel_deg_per_100m", s.r_rel_deg_per_100m}});
      j["kitti"] = {{"t_rel_pct", kitti->t_rel_pct},
                    {"r_rel_deg_per_100m", kitti->r_rel_deg_per_100m},
                    {"count", kitti->count},
                    {"segments", segs}};
    } else {
      j["kitti"] = nullptr;
    }
  }
  if (!o.plot_path.empty()) {
    eval::PlotOptions po;
    char title[160];
    std::snprintf(title, sizeof(title), "ATE RMSE %.3f m over %zu poses (%s alignment)", ate.translation_m.rmse,
                  pairs.size(), eval::to_string(align).c_str());
    po.title = title;
    eval::save_top_view(o.plot_path, ate.p_gt, ate.p_est_aligned, po);
  }
}

// The wheel-odometry consistency figures (stdout, and into `j`).
void compare_with_odometry(const Options& o, const agvslam::Trajectory& est, bool first_line, nlohmann::json& j) {
  const eval::BodyAxes est_axes = eval::parse_body_axes(o.est_axes, "--est-axes");
  const eval::BodyAxes odometry_axes = eval::parse_body_axes(o.odometry_axes, "--odometry-axes");
  const bool csv =
      o.odometry_format.empty() ? agvslam::io::looks_like_odometry_csv(o.odometry_path) : o.odometry_format == "csv";
  eval::PlanarTrack odometry;
  if (csv) {
    odometry = eval::planar_track(agvslam::io::read_odometry_csv(o.odometry_path));
  } else {
    TrajectoryFormat format{};
    odometry =
        eval::planar_track(load(o.odometry_path, o.odometry_format, "--odometry-format", "", &format), odometry_axes);
  }
  const eval::OdometryCheckResult r =
      eval::check_against_odometry(est, est_axes, odometry, o.odometry, o.odometry_path);
  if (first_line) std::printf("ODOMETRY_DISTANCE_RATIO %.6f\n", r.distance_ratio);
  std::printf("odometry: %zu poses over %.1f s compared with %s (%s)\n", r.frames_compared, r.duration_s,
              o.odometry_path.c_str(), csv ? "speed / yaw rate" : "poses");
  std::printf("distance: trajectory %.3f m, odometry %.3f m, ratio %.4f (%s the %.0f %% tolerance)\n",
              r.trajectory_distance_m, r.odometry_distance_m, r.distance_ratio,
              r.distance_within_tolerance ? "within" : "OUTSIDE", 100 * o.odometry.distance_tolerance);
  std::printf("speed: RMSE %.4f m/s over %zu windows of %.2f s\n", r.speed_rmse_mps, r.windows, o.odometry.window_s);
  std::printf(
      "heading change: trajectory %.2f deg, odometry %.2f deg, difference %.2f deg (largest on the way %.2f "
      "deg)\n",
      r.trajectory_heading_change_deg, r.odometry_heading_change_deg, r.heading_difference_deg,
      r.max_heading_difference_deg);
  std::printf("disagreements (> %.0f %%): %zu of %zu windows\n", 100 * o.odometry.disagreement_ratio,
              r.disagreeing_windows, r.windows);
  nlohmann::json ranges = nlohmann::json::array();
  for (const auto& d : r.disagreements) {
    std::printf("  frames %zu-%zu (%.2f-%.2f s): trajectory %.3f m / %.1f deg, odometry %.3f m / %.1f deg\n",
                d.first_frame, d.last_frame, d.t_first_s, d.t_last_s, d.trajectory_m, d.trajectory_heading_deg,
                d.odometry_m, d.odometry_heading_deg);
    ranges.push_back({{"first_frame", d.first_frame},
                      {"last_frame", d.last_frame},
                      {"t_first_s", d.t_first_s},
                      {"t_last_s", d.t_last_s},
                      {"trajectory_m", d.trajectory_m},
                      {"odometry_m", d.odometry_m},
                      {"trajectory_heading_deg", d.trajectory_heading_deg},
                      {"odometry_heading_deg", d.odometry_heading_deg}});
  }
  j["odometry"] = {{"file", o.odometry_path},
                   {"frames_compared", r.frames_compared},
                   {"duration_s", r.duration_s},
                   {"trajectory_distance_m", r.trajectory_distance_m},
                   {"odometry_distance_m", r.odometry_distance_m},
                   {"distance_ratio", r.distance_ratio},
                   {"distance_within_tolerance", r.distance_within_tolerance},
                   {"speed_rmse_mps", r.speed_rmse_mps},
                   {"windows", r.windows},
                   {"trajectory_heading_change_deg", r.trajectory_heading_change_deg},
                   {"odometry_heading_change_deg", r.odometry_heading_change_deg},
                   {"heading_difference_deg", r.heading_difference_deg},
                   {"max_heading_difference_deg", r.max_heading_difference_deg},
                   {"disagreeing_windows", r.disagreeing_windows},
                   {"disagreements", ranges}};
}

int run(const Options& o) {
  // Options first, before any file is read.
  const eval::AlignMode align = eval::parse_align_mode(o.align);
  if (o.gt_path.empty() && o.odometry_path.empty())
    throw InputError("--gt", "", "expected --gt FILE (ground truth) or --odometry FILE (wheel odometry), or both");
  if (!o.odometry_format.empty() && o.odometry_format != "csv") {
    agvslam::io::parse_trajectory_format(o.odometry_format, "--odometry-format");
  }
  TrajectoryFormat est_format{};
  const agvslam::Trajectory est = load(o.est_path, o.est_format, "--est-format", o.times_path, &est_format);
  if (est.empty()) throw InputError(o.est_path, "", "expected at least one pose, found none");
  nlohmann::json j;
  if (!o.gt_path.empty()) compare_with_ground_truth(o, align, est, est_format, j);
  if (!o.odometry_path.empty()) compare_with_odometry(o, est, o.gt_path.empty(), j);
  if (!o.json_path.empty()) agvslam::io::write_file_atomically(o.json_path, j.dump(2) + "\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results, starting with the ATE_RMSE_M line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-eval"));
  CLI::App app{
      "agvslam-eval: ATE, RPE and KITTI relative errors of an estimated trajectory against ground truth; "
      "its consistency with wheel odometry"};
  Options o;
  app.add_option("--gt", o.gt_path, "ground-truth trajectory file");
  app.add_option("--est", o.est_path, "estimated trajectory file")->required();
  app.add_option("--gt-format", o.gt_format, "kitti|tum|euroc (default: guessed from the file)");
  app.add_option("--est-format", o.est_format, "kitti|tum|euroc (default: guessed from the file)");
  app.add_option("--times", o.times_path, "KITTI times.txt giving time stamps to KITTI-format files");
  app.add_option("--align", o.align, "se3|sim3|none")->capture_default_str();
  app.add_option("--max-dt-ms", o.max_dt_ms, "largest time difference for association by time stamp")
      ->capture_default_str();
  app.add_option("--rpe-delta", o.rpe_delta, "frame step of the relative pose error")->capture_default_str();
  app.add_option("--json", o.json_path, "write every figure to this JSON file");
  app.add_option("--plot", o.plot_path, "write a top-view PNG of both trajectories (with --gt)");
  app.add_option(
      "--odometry", o.odometry_path,
      "wheel odometry to check the trajectory against: poses (TUM / EuRoC) or CSV t_s,speed_mps,yaw_rate_radps");
  app.add_option("--odometry-format", o.odometry_format, "tum|euroc|csv (default: guessed from the file)");
  app.add_option("--est-axes", o.est_axes,
                 "body axes of the estimate: camera (x right, y down, z forward) or base "
                 "(x forward, z up)")
      ->capture_default_str();
  app.add_option("--odometry-axes", o.odometry_axes, "body axes of odometry poses: camera or base")
      ->capture_default_str();
  app.add_option("--odometry-window-s", o.odometry.window_s, "window over which speeds are compared (s)")
      ->capture_default_str()
      ->check(CLI::Range(0.05, 60.0));
  app.add_option("--odometry-disagreement", o.odometry.disagreement_ratio,
                 "a window disagrees when distances (or headings while turning) differ by more than this fraction")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 10.0));
  app.add_option("--odometry-tolerance", o.odometry.distance_tolerance,
                 "|distance ratio - 1| accepted over the run (the odometry's own scale error)")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
