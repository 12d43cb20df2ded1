// agvslam-vocab: trains the bag-of-binary-words vocabulary on ORB descriptors of images, evaluates vocabularies on
// place-recognition revisits, and prints a vocabulary file's header.
//
//   train:    agvslam-vocab (--images DIR[,DIR...] | --datasets DIR[,DIR...]) --out FILE [--k 10] [--levels 5]
//                           [--max-features-per-image N] [--frame-step N] [--seed S] [--threads N]
//                           [--max-iterations N] [--params-features params/features.yaml] [--description TEXT]
//                           [--json FILE]
//   evaluate: agvslam-vocab --evaluate --vocabulary FILE[,FILE...] (--loop DIR[,DIR...] | --map DIR --query DIR)
//                           [--frame-step N] [--max-distance-m 1] [--max-angle-deg 20] [--min-gap-s 10]
//                           [--threshold S] [--params-features FILE] [--params-sim FILE] [--threads N] [--json FILE]
//   info:     agvslam-vocab --info FILE
//
// Features are the project's ORB (agvslam::features::OrbExtractor with params/features.yaml, the SLAM's own
// descriptors) on the left image of each frame. --images: every image file (png, jpg, pgm, ppm, bmp) of each
// folder, sorted by name. --datasets: a sequence folder (KITTI layout as agvslam-sim writes it, or EuRoC), or a
// folder whose sub-folders are sequences (all of them, sorted). --frame-step N uses every N-th image or frame.
// --max-features-per-image N keeps a seeded random subset of N descriptors of an image that has more (0: all).
//
// Evaluation (see agvslam/place/revisit_evaluation.h): --loop DIR queries every frame of a sequence against its
// frames at least --min-gap-s older (loop closing); --map DIR --query DIR queries every frame of one sequence
// against all frames of another (relocalisation). Sequences need ground-truth poses (poses.txt). --map/--query
// must be simulator folders of one warehouse (the same --layout-seed): their poses are brought into the
// warehouse's frame from scenario.json. For each vocabulary, stdout gets one line per evaluation:
//   PR <vocabulary> <mode> <sequence> positives P queries Q AP a R@P1 r1 (t t1) R@P0.95 r2 (t t2) P@R0.5 p
//      max_false s at_threshold(t): P p R r
// (R@P1: the largest recall at precision 1 and the score threshold reaching it; max_false: the best score of a
// wrong top-1 answer.) Then TRANSFORM <vocabulary> median_ms / p95_ms of the transform per frame.
// Exit status: 0 on success, 2 on bad input (the message names the option, file or folder), 1 on other failures.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <random>

#include "agvslam/core/clock.h"
#include "agvslam/core/error.h"
#include "agvslam/core/parallel_for.h"
#include "agvslam/features/features_config.h"
#include "agvslam/features/orb_extractor.h"
#include "agvslam/io/dataset.h"
#include "agvslam/io/trajectory_io.h"
#include "agvslam/place/revisit_evaluation.h"
#include "agvslam/place/vocabulary.h"
#include "agvslam/sim/sim_config.h"
#include "agvslam/sim/simulator.h"
#include "tool_main.h"

namespace {

namespace fs = std::filesystem;
using agvslam::ms_since;
namespace place = agvslam::place;
using agvslam::InputError;
using Clock = std::chrono::steady_clock;
using json = nlohmann::json;

struct Options {
  std::vector<std::string> images, datasets, vocabularies, loops;
  std::string out, params_features, params_sim, description, json_path, info, map, query;
  bool evaluate = false;
  int k = 10, levels = 5, max_features = 0, frame_step = 1, threads = 1, max_iterations = 20;
  uint64_t seed = 1;
  double max_distance_m = 1.0, max_angle_deg = 20.0, min_gap_s = 10.0;
  float threshold = 0.f;
};

json stats_of(std::vector<double> v) {
  if (v.empty()) return {{"median", nullptr}, {"p95", nullptr}, {"max", nullptr}, {"count", 0}};
  std::sort(v.begin(), v.end());
  auto at = [&](double q) { return v[std::min(v.size() - 1, std::size_t(q * double(v.size() - 1) + 0.5))]; };
  return {{"median", at(0.5)}, {"p95", at(0.95)}, {"max", v.back()}, {"count", v.size()}};
}

// One image to extract features from: a label for messages and how to load it (CV_8UC1).
struct ImageItem {
  std::string label;
  std::function<cv::Mat()> load;
};

bool is_image_file(const fs::path& p) {
  std::string ext = p.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".pgm" || ext == ".ppm" || ext == ".bmp";
}

cv::Mat read_grey(const std::string& path) {
  cv::Mat m = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (m.empty()) throw InputError(path, "", "expected a readable image");
  return m;
}

std::vector<ImageItem> image_folder_items(const std::string& dir, int step) {
  if (!fs::is_directory(dir)) throw InputError("--images", dir, "expected a folder of images");
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && is_image_file(e.path())) files.push_back(e.path().string());
  std::sort(files.begin(), files.end());
  if (files.empty()) throw InputError("--images", dir, "expected image files (png, jpg, pgm, ppm, bmp)");
  std::vector<ImageItem> items;
  for (std::size_t i = 0; i < files.size(); i += std::size_t(step))
    items.push_back({files[i], [p = files[i]] { return read_grey(p); }});
  return items;
}

bool looks_like_dataset(const fs::path& dir) {
  return fs::is_directory(dir / "mav0") || fs::is_directory(dir / "image_0") || fs::is_directory(dir / "image_l");
}

// A dataset folder, or a folder of dataset folders.
std::vector<std::string> expand_datasets(const std::string& dir, const std::string& option) {
  if (!fs::is_directory(dir)) throw InputError(option, dir, "expected a sequence folder or a folder of sequences");
  if (looks_like_dataset(dir)) return {dir};
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_directory() && looks_like_dataset(e.path())) out.push_back(e.path().string());
  std::sort(out.begin(), out.end());
  if (out.empty())
    throw InputError(option, dir, "expected a sequence (image_0/ or mav0/) or sub-folders that are sequences");
  return out;
}

std::vector<ImageItem> dataset_items(const std::string& dir, int step) {
  std::shared_ptr<agvslam::io::StereoDataset> ds = agvslam::io::open_dataset(dir);
  std::vector<ImageItem> items;
  const auto* kitti = dynamic_cast<const agvslam::io::KittiDataset*>(ds.get());
  for (std::size_t i = 0; i < ds->size(); i += std::size_t(step)) {
    const std::string label = dir + " frame " + std::to_string(i);
    if (kitti)
      items.push_back({label, [p = kitti->left_path(i)] { return read_grey(p); }});
    else
      items.push_back({label, [ds, i] { return ds->frame(i).left; }});
  }
  return items;
}

// A seeded subset of `max_features` rows of d (the same for any thread count).
cv::Mat subset_rows(const cv::Mat& d, int max_features, uint64_t seed, std::size_t item) {
  std::vector<int> rows(std::size_t(d.rows));
  for (int r = 0; r < d.rows; ++r) rows[std::size_t(r)] = r;
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ULL + item);
  for (int r = 0; r < max_features; ++r)
    std::swap(rows[std::size_t(r)], rows[std::size_t(r) + std::size_t(rng() % uint64_t(d.rows - r))]);
  std::sort(rows.begin(), rows.begin() + max_features);
  cv::Mat sub(max_features, d.cols, d.type());
  for (int r = 0; r < max_features; ++r) d.row(rows[std::size_t(r)]).copyTo(sub.row(r));
  return sub;
}

// Extracts ORB descriptors of every item with `threads` extractors; out[i] for items[i].
void extract_all(const std::vector<ImageItem>& items, const agvslam::features::OrbExtractorConfig& orb, int threads,
                 int max_features, uint64_t seed, std::vector<cv::Mat>& out, std::vector<double>* times_ms = nullptr) {
  out.assign(items.size(), cv::Mat());
  std::vector<double> times(items.size(), 0.0);
  struct Extractor {
    agvslam::features::OrbExtractor orb;
    agvslam::features::KeypointSet keypoints;
  };
  std::vector<std::unique_ptr<Extractor>> extractors(std::size_t(std::max(1, threads)));  // one per worker
  std::atomic<std::size_t> done{0};
  std::mutex log_mutex;
  agvslam::parallel_for(threads, items.size(), 1, [&](std::size_t begin, std::size_t end, int worker) {
    auto& extractor = extractors[std::size_t(worker)];
    if (!extractor) extractor = std::make_unique<Extractor>(Extractor{agvslam::features::OrbExtractor(orb), {}});
    for (std::size_t i = begin; i < end; ++i) {
      const cv::Mat image = items[i].load();
      const auto t0 = Clock::now();
      extractor->orb.extract(image, cv::Mat(), extractor->keypoints);
      times[i] = ms_since(t0);
      const cv::Mat& d = extractor->keypoints.descriptors;
      out[i] = max_features > 0 && d.rows > max_features ? subset_rows(d, max_features, seed, i) : d.clone();
      const std::size_t n = ++done;
      if (n % std::max<std::size_t>(1, items.size() / 20) == 0 || n == items.size()) {
        std::lock_guard lock(log_mutex);
        spdlog::info("features: {}/{} images", n, items.size());
      }
    }
  });
  if (times_ms) *times_ms = times;
}

agvslam::features::OrbExtractorConfig load_orb(const std::string& path) {
  if (path.empty()) return {};
  return agvslam::features::load_features_config(path).orb;
}

int train(const Options& o) {
  place::VocabularyTrainingConfig cfg;
  cfg.branching = o.k;
  cfg.levels = o.levels;
  cfg.seed = o.seed;
  cfg.threads = o.threads;
  cfg.max_iterations = o.max_iterations;
  cfg.validate("command line (--k, --levels, --threads, --max-iterations)");
  const auto orb = load_orb(o.params_features);
  if (o.out.empty()) throw InputError("--out", "", "expected the vocabulary file to write");
  spdlog::info("agvslam-vocab: train");
  spdlog::info("  {}", cfg.describe());
  spdlog::info("  features: {} (from {})", orb.describe(),
               o.params_features.empty() ? "built-in defaults" : o.params_features);
  spdlog::info("  max features per image {} (0: all), frame step {}, out {}", o.max_features, o.frame_step, o.out);

  std::vector<ImageItem> items;
  std::vector<std::string> sources;
  for (const auto& dir : o.images) {
    auto more = image_folder_items(dir, o.frame_step);
    spdlog::info("  images: {} ({} images)", dir, more.size());
    sources.push_back(fs::path(dir).filename().string());
    items.insert(items.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
  }
  for (const auto& arg : o.datasets) {
    const auto dirs = expand_datasets(arg, "--datasets");
    std::size_t n = 0;
    for (const auto& dir : dirs) {
      auto more = dataset_items(dir, o.frame_step);
      n += more.size();
      sources.push_back(fs::path(dir).filename().string());
      items.insert(items.end(), std::make_move_iterator(more.begin()), std::make_move_iterator(more.end()));
    }
    spdlog::info("  datasets: {} ({} sequences, {} frames)", arg, dirs.size(), n);
  }
  if (items.empty()) throw InputError("--images/--datasets", "", "expected at least one image");

  const auto t_extract = Clock::now();
  std::vector<cv::Mat> descriptors;
  std::vector<double> extract_ms;
  cv::setNumThreads(1);
  extract_all(items, orb, o.threads, o.max_features, o.seed, descriptors, &extract_ms);
  place::DescriptorSet set;
  std::size_t total = 0;
  for (const auto& d : descriptors) total += std::size_t(d.rows);
  set.reserve(total, descriptors.size());
  for (const auto& d : descriptors) set.add_image(d);
  std::vector<cv::Mat>().swap(descriptors);
  const double extract_s = ms_since(t_extract) / 1000;
  spdlog::info("features: {} descriptors from {} images in {:.1f} s", set.size(), set.image_count(), extract_s);

  std::string description = o.description.empty() ? "" : o.description + "\n";
  description += "agvslam-vocab: " + cfg.describe() + "\nfeatures: " + orb.describe() + "\nmax features per image " +
                 std::to_string(o.max_features) + ", frame step " + std::to_string(o.frame_step) + "\n" +
                 std::to_string(set.image_count()) + " images, " + std::to_string(set.size()) + " descriptors, from " +
                 std::to_string(sources.size()) + " sources: ";
  for (std::size_t i = 0; i < sources.size(); ++i) description += (i ? " " : "") + sources[i];
  description += "\n";

  const auto t_train = Clock::now();
  const place::Vocabulary v =
      place::Vocabulary::train(set, cfg, description, [](const std::string& line) { spdlog::info("train: {}", line); });
  const double train_s = ms_since(t_train) / 1000;
  v.save(o.out);
  const auto t_load = Clock::now();
  const place::Vocabulary check = place::Vocabulary::load(o.out);
  const double load_ms = ms_since(t_load);
  if (check.identity() != v.identity()) throw std::runtime_error("the written file does not read back identically");
  const auto bytes = fs::file_size(o.out);
  spdlog::info("wrote {}: {} bytes, {}; loads in {:.1f} ms", o.out, bytes, v.describe(), load_ms);
  std::printf("VOCABULARY %s k %d L %d words %zu nodes %zu bytes %llu identity %s load_ms %.1f train_s %.1f\n",
              o.out.c_str(), v.branching(), v.levels(), v.word_count(), v.node_count(),
              static_cast<unsigned long long>(bytes), v.identity_hex().c_str(), load_ms, train_s);
  if (!o.json_path.empty()) {
    json j = {{"out", o.out},
              {"k", v.branching()},
              {"levels", v.levels()},
              {"words", v.word_count()},
              {"nodes", v.node_count()},
              {"bytes", bytes},
              {"identity", v.identity_hex()},
              {"images", set.image_count()},
              {"descriptors", set.size()},
              {"timings",
               {{"extract_total_s", extract_s},
                {"train_s", train_s},
                {"load_ms", load_ms},
                {"extract_ms", stats_of(extract_ms)}}}};
    agvslam::io::write_file_atomically(o.json_path, j.dump(2) + "\n");
  }
  return 0;
}

// ---- evaluation ---------------------------------------------------------------------------------------------

struct Sequence {
  std::string dir;
  std::vector<cv::Mat> descriptors;
  std::vector<agvslam::SE3d> T_w_c;
  std::vector<int64_t> t_ns;
  std::vector<double> extract_ms;
};

// Poses of a simulator sequence in its warehouse's frame (from scenario.json; the simulator rebuilds the scenario
// without rendering).
agvslam::SE3d T_map_w_of_simulator_folder(const std::string& dir, const agvslam::sim::SimConfig& config) {
  const std::string path = (fs::path(dir) / "scenario.json").string();
  std::ifstream in(path);
  if (!in) throw InputError(path, "", "expected scenario.json of an agvslam-sim folder (--map/--query)");
  json j;
  try {
    in >> j;
    agvslam::sim::ScenarioOptions s;
    s.name = j.at("scenario").get<std::string>();
    s.frames = j.at("frames").get<int>();
    s.seed = j.at("seed").get<uint64_t>();
    s.layout_seed = j.at("layout_seed").get<uint64_t>();
    s.start_offset_m = j.at("start_offset_m").get<double>();
    const agvslam::sim::Simulator sim(config, s);
    return sim.T_w_map().inverse();
  } catch (const json::exception& e) {
    throw InputError(path, "",
                     std::string("expected scenario, frames, seed, layout_seed, start_offset_m: ") + e.what());
  }
}

Sequence load_sequence(const std::string& dir, const Options& o, const agvslam::features::OrbExtractorConfig& orb,
                       const agvslam::SE3d& T_frame_w = agvslam::SE3d::Identity()) {
  const auto ds = agvslam::io::open_dataset(dir);
  const auto gt = ds->ground_truth();
  if (!gt || gt->size() < ds->size())
    throw InputError(dir, "poses.txt", "expected a ground-truth pose for every frame (evaluation needs them)");
  Sequence s;
  s.dir = dir;
  const auto items = dataset_items(dir, o.frame_step);
  extract_all(items, orb, o.threads, 0, 0, s.descriptors, &s.extract_ms);
  for (std::size_t i = 0; i < ds->size(); i += std::size_t(o.frame_step)) {
    s.T_w_c.push_back(T_frame_w * (*gt)[i].T_w_c);
    s.t_ns.push_back(ds->timestamp_ns(i));
  }
  spdlog::info("sequence {}: {} frames", dir, s.t_ns.size());
  return s;
}

std::vector<place::PlaceSample> samples_of(const Sequence& s, const place::Vocabulary& v, std::vector<double>& ms) {
  std::vector<place::PlaceSample> out(s.descriptors.size());
  place::FeatureVector fv;
  for (std::size_t i = 0; i < out.size(); ++i) {
    const auto t0 = Clock::now();
    v.transform(s.descriptors[i], out[i].bow, fv, std::min(2, v.levels()));
    ms.push_back(ms_since(t0));
    out[i].T_w_c = s.T_w_c[i];
    out[i].t_ns = s.t_ns[i];
  }
  return out;
}

json report(const std::string& vocabulary, const std::string& mode, const std::string& sequence,
            const place::RevisitEvaluation& e, float threshold) {
  float t100 = 0, t95 = 0;
  const double r100 = e.recall_at_precision(1.0, &t100), r95 = e.recall_at_precision(0.95, &t95);
  const place::PrPoint at = e.at_threshold(threshold);
  float max_false = 0;  // the best score of a wrong answer: a loop threshold must stay above it
  for (const auto& q : e.queries)
    if (q.match >= 0 && !q.correct) max_false = std::max(max_false, q.score);
  std::printf(
      "PR %s %s %s positives %d queries %zu AP %.3f R@P1 %.3f (t %.3f) R@P0.95 %.3f (t %.3f) "
      "P@R0.5 %.3f max_false %.3f at_threshold(%.3f): P %.3f R %.3f\n",
      fs::path(vocabulary).filename().c_str(), mode.c_str(), fs::path(sequence).filename().c_str(), e.positives,
      e.queries.size(), e.average_precision, r100, double(t100), r95, double(t95), e.precision_at_recall(0.5),
      double(max_false), double(threshold), at.precision, at.recall);
  json curve = json::array();
  for (const auto& p : e.curve)
    curve.push_back({{"threshold", p.threshold},
                     {"precision", p.precision},
                     {"recall", p.recall},
                     {"tp", p.true_positives},
                     {"fp", p.false_positives}});
  json queries = json::array();
  for (const auto& q : e.queries)
    queries.push_back({{"query", q.query},
                       {"match", q.match},
                       {"score", q.score},
                       {"positive", q.positive},
                       {"correct", q.correct},
                       {"distance_m", q.match_distance_m},
                       {"angle_deg", q.match_angle_deg}});
  return {{"vocabulary", vocabulary},
          {"mode", mode},
          {"sequence", sequence},
          {"positives", e.positives},
          {"queries", e.queries.size()},
          {"average_precision", e.average_precision},
          {"recall_at_precision_1", r100},
          {"threshold_at_precision_1", t100},
          {"recall_at_precision_0.95", r95},
          {"threshold_at_precision_0.95", t95},
          {"precision_at_recall_0.5", e.precision_at_recall(0.5)},
          {"max_false_score", max_false},
          {"at_threshold", {{"threshold", threshold}, {"precision", at.precision}, {"recall", at.recall}}},
          {"curve", curve},
          {"per_query", queries}};
}

int evaluate(const Options& o) {
  if (o.vocabularies.empty()) throw InputError("--vocabulary", "", "expected one or more vocabulary files");
  if (o.loops.empty() && (o.map.empty() || o.query.empty()))
    throw InputError("--loop/--map/--query", "", "expected --loop DIR[,DIR...] and/or both --map DIR and --query DIR");
  if (o.map.empty() != o.query.empty())
    throw InputError(o.map.empty() ? "--map" : "--query", "", "expected --map and --query together");
  place::RevisitCriteria criteria;
  criteria.max_distance_m = o.max_distance_m;
  criteria.max_angle_deg = o.max_angle_deg;
  criteria.min_time_gap_s = o.min_gap_s;
  const auto orb = load_orb(o.params_features);
  spdlog::info("agvslam-vocab: evaluate");
  spdlog::info("  {}", criteria.describe());
  spdlog::info("  features: {}; frame step {}; threads {}; reported threshold {}", orb.describe(), o.frame_step,
               o.threads, o.threshold);

  json j = {{"criteria",
             {{"max_distance_m", o.max_distance_m}, {"max_angle_deg", o.max_angle_deg}, {"min_gap_s", o.min_gap_s}}},
            {"vocabularies", json::array()},
            {"evaluations", json::array()}};
  std::vector<place::Vocabulary> vocabularies;
  for (const auto& path : o.vocabularies) {
    const auto t0 = Clock::now();
    vocabularies.push_back(place::Vocabulary::load(path));
    const double load_ms = ms_since(t0);
    const auto& v = vocabularies.back();
    spdlog::info("{}: {} ({:.1f} ms to load)", path, v.describe(), load_ms);
    j["vocabularies"].push_back({{"file", path},
                                 {"k", v.branching()},
                                 {"levels", v.levels()},
                                 {"words", v.word_count()},
                                 {"bytes", fs::file_size(path)},
                                 {"identity", v.identity_hex()},
                                 {"load_ms", load_ms}});
  }
  cv::setNumThreads(1);
  std::vector<Sequence> loops;
  for (const auto& arg : o.loops)
    for (const auto& dir : expand_datasets(arg, "--loop")) loops.push_back(load_sequence(dir, o, orb));
  Sequence map, query;
  if (!o.map.empty()) {
    agvslam::sim::SimConfig sim_config;
    if (!o.params_sim.empty()) sim_config = agvslam::sim::load_sim_config(o.params_sim);
    map = load_sequence(o.map, o, orb, T_map_w_of_simulator_folder(o.map, sim_config));
    query = load_sequence(o.query, o, orb, T_map_w_of_simulator_folder(o.query, sim_config));
  }
  for (std::size_t vi = 0; vi < vocabularies.size(); ++vi) {
    const auto& v = vocabularies[vi];
    const auto& name = o.vocabularies[vi];
    std::vector<double> transform_ms;
    for (const auto& s : loops) {
      const auto e = place::evaluate_loop_revisits(samples_of(s, v, transform_ms), criteria, v.word_count());
      j["evaluations"].push_back(report(name, "loop", s.dir, e, o.threshold));
    }
    if (!o.map.empty()) {
      const auto m = samples_of(map, v, transform_ms);
      const auto q = samples_of(query, v, transform_ms);
      const auto e = place::evaluate_relocalisation(m, q, criteria, v.word_count());
      j["evaluations"].push_back(report(name, "relocalisation", o.query, e, o.threshold));
    }
    j["vocabularies"][vi]["transform_ms"] = stats_of(transform_ms);
    const json st = stats_of(transform_ms);
    std::printf("TRANSFORM %s median_ms %.3f p95_ms %.3f\n", fs::path(name).filename().c_str(),
                st["median"].is_null() ? 0.0 : st["median"].get<double>(),
                st["p95"].is_null() ? 0.0 : st["p95"].get<double>());
  }
  if (!o.json_path.empty()) agvslam::io::write_file_atomically(o.json_path, j.dump(1) + "\n");
  return 0;
}

int info(const Options& o) {
  const auto t0 = Clock::now();
  const place::Vocabulary v = place::Vocabulary::load(o.info);
  const double load_ms = ms_since(t0);
  std::printf("%s\nfile %s: %llu bytes, loaded and verified in %.1f ms\n%s", v.describe().c_str(), o.info.c_str(),
              static_cast<unsigned long long>(fs::file_size(o.info)), load_ms, v.description().c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  spdlog::set_default_logger(spdlog::stderr_color_mt("agvslam-vocab"));
  CLI::App app{
      "agvslam-vocab: train a bag-of-binary-words vocabulary on the project's ORB descriptors, evaluate "
      "vocabularies on place-recognition revisits, or print a vocabulary file's header"};
  Options o;
  app.add_option("--images", o.images, "folders of images to train on")->delimiter(',');
  app.add_option("--datasets", o.datasets, "sequence folders (or folders of sequences) to train on")->delimiter(',');
  app.add_option("--out", o.out, "vocabulary file to write");
  app.add_option("--k", o.k, "branching factor")->capture_default_str();
  app.add_option("--levels", o.levels, "depth of the tree (L)")->capture_default_str();
  app.add_option("--max-features-per-image", o.max_features, "keep at most N descriptors per image (0: all)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--frame-step", o.frame_step, "use every N-th image or frame")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--seed", o.seed, "training seed (k-means++, feature subsets)")->capture_default_str();
  app.add_option("--threads", o.threads, "threads for features and training (the result does not depend on it)")
      ->check(CLI::Range(1, 256))
      ->capture_default_str();
  app.add_option("--max-iterations", o.max_iterations, "k-medians iterations per node")->capture_default_str();
  app.add_option("--params-features", o.params_features,
                 "ORB settings (params/features.yaml; default: that file when it exists, else built-in)");
  app.add_option("--description", o.description, "what the vocabulary is trained on (stored in the file)");
  app.add_option("--json", o.json_path, "write figures and per-stage timings as JSON");
  app.add_flag("--evaluate", o.evaluate, "evaluate vocabularies on revisits instead of training");
  app.add_option("--vocabulary", o.vocabularies, "vocabulary files to evaluate")->delimiter(',');
  app.add_option("--loop", o.loops, "sequences (or folders of sequences) for loop revisits")->delimiter(',');
  app.add_option("--map", o.map, "simulator sequence whose frames form the database (relocalisation)");
  app.add_option("--query", o.query, "simulator sequence of the same warehouse whose frames are the queries");
  app.add_option("--max-distance-m", o.max_distance_m, "same place: cameras within this distance")
      ->capture_default_str();
  app.add_option("--max-angle-deg", o.max_angle_deg, "same place: relative rotation within this angle")
      ->capture_default_str();
  app.add_option("--min-gap-s", o.min_gap_s, "loop revisits: database frames at least this much older")
      ->capture_default_str();
  app.add_option("--threshold", o.threshold, "score threshold reported with its precision and recall")
      ->capture_default_str();
  app.add_option("--params-sim", o.params_sim, "simulator settings the --map/--query folders were rendered with");
  app.add_option("--info", o.info, "print a vocabulary file's header and description");
  return agvslam::apps::parse_and_run(app, argc, argv, [&] {
    if (o.params_features.empty() && fs::exists("params/features.yaml")) o.params_features = "params/features.yaml";
    if (!o.info.empty()) return info(o);
    if (o.evaluate) return evaluate(o);
    if (o.images.empty() && o.datasets.empty())
      throw InputError("--images/--datasets", "", "expected folders to train on (or --evaluate, or --info FILE)");
    return train(o);
  });
}
