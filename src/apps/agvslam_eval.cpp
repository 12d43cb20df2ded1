// agvslam-eval: compares an estimated trajectory with ground truth.
//
//   agvslam-eval --gt FILE --est FILE [--gt-format kitti|tum|euroc] [--est-format kitti|tum|euroc]
//                [--times FILE] [--align se3|sim3|none] [--max-dt-ms MS] [--json OUT] [--plot OUT.png]
//
// Association is by index when both files are KITTI poses without times; otherwise by nearest time stamp
// (--times gives KITTI files their time stamps). The first line of stdout is `ATE_RMSE_M <value>`.
// Exit status: 0 on success, 2 on bad input (with a message naming the file or option), 1 on any other failure.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "agvslam/core/error.h"
#include "agvslam/eval/metrics.h"
#include "agvslam/eval/plot.h"
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

int run(const Options& o) {
  const eval::AlignMode align = eval::parse_align_mode(o.align);  // options first, before any file is read
  TrajectoryFormat gt_format{}, est_format{};
  const agvslam::Trajectory gt = load(o.gt_path, o.gt_format, "--gt-format", o.times_path, &gt_format);
  const agvslam::Trajectory est = load(o.est_path, o.est_format, "--est-format", o.times_path, &est_format);
  if (gt.empty()) throw InputError(o.gt_path, "", "expected at least one pose, found none");
  if (est.empty()) throw InputError(o.est_path, "", "expected at least one pose, found none");

  const bool by_index =
      gt_format == TrajectoryFormat::kKitti && est_format == TrajectoryFormat::kKitti && o.times_path.empty();
  if (!by_index && o.times_path.empty() &&
      (gt_format == TrajectoryFormat::kKitti || est_format == TrajectoryFormat::kKitti))
    throw InputError("--times", "", "a KITTI pose file has no time stamps: give --times times.txt to associate it "
                     "with a time-stamped (TUM/EuRoC) trajectory");
  const eval::PosePairs pairs =
      by_index ? eval::associate_by_index(gt, est)
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
  std::printf("poses: %zu associated (%s) of %zu estimated, %zu ground truth; ground-truth path %.3f m\n",
              pairs.size(), by_index ? "by index" : "by time stamp", est.size(), gt.size(), gt_length);
  std::printf("alignment: %s", eval::to_string(align).c_str());
  if (align == eval::AlignMode::kSim3) std::printf(" (scale %.6f)", ate.alignment.scale);
  std::printf("\n");
  const auto& a = ate.translation_m;
  std::printf("ATE [m]:       rmse %.6f  mean %.6f  median %.6f  std %.6f  max %.6f\n", a.rmse, a.mean, a.median,
              a.std, a.max);
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

  if (!o.json_path.empty()) {
    nlohmann::json j;
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
        segs.push_back({{"length_m", s.length_m}, {"count", s.count}, {"t_rel_pct", s.t_rel_pct},
                        {"r_rel_deg_per_100m", s.r_rel_deg_per_100m}});
      j["kitti"] = {{"t_rel_pct", kitti->t_rel_pct}, {"r_rel_deg_per_100m", kitti->r_rel_deg_per_100m},
                    {"count", kitti->count}, {"segments", segs}};
    } else {
      j["kitti"] = nullptr;
    }
    agvslam::io::write_file_atomically(o.json_path, j.dump(2) + "\n");
  }
  if (!o.plot_path.empty()) {
    eval::PlotOptions po;
    char title[160];
    std::snprintf(title, sizeof(title), "ATE RMSE %.3f m over %zu poses (%s alignment)", ate.translation_m.rmse,
                  pairs.size(), eval::to_string(align).c_str());
    po.title = title;
    eval::save_top_view(o.plot_path, ate.p_gt, ate.p_est_aligned, po);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // Logs go to stderr: stdout carries the results, starting with the ATE_RMSE_M line.
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-eval"));
  CLI::App app{"agvslam-eval: ATE, RPE and KITTI relative errors of an estimated trajectory against ground truth"};
  Options o;
  app.add_option("--gt", o.gt_path, "ground-truth trajectory file")->required();
  app.add_option("--est", o.est_path, "estimated trajectory file")->required();
  app.add_option("--gt-format", o.gt_format, "kitti|tum|euroc (default: guessed from the file)");
  app.add_option("--est-format", o.est_format, "kitti|tum|euroc (default: guessed from the file)");
  app.add_option("--times", o.times_path, "KITTI times.txt giving time stamps to KITTI-format files");
  app.add_option("--align", o.align, "se3|sim3|none")->capture_default_str();
  app.add_option("--max-dt-ms", o.max_dt_ms, "largest time difference for association by time stamp")
      ->capture_default_str();
  app.add_option("--rpe-delta", o.rpe_delta, "frame step of the relative pose error")->capture_default_str();
  app.add_option("--json", o.json_path, "write every figure to this JSON file");
  app.add_option("--plot", o.plot_path, "write a top-view PNG of both trajectories");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] { return run(o); });
}
