#include "agvslam/slam/map_io.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <zlib.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include "agvslam/core/error.h"
#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/map_point.h"

namespace agvslam::slam {

// Friend of KeyFrame and Map: reads and restores what the public interface does not expose.
struct MapFileAccess {
  static const std::vector<std::pair<KeyFrame*, int>>& connections(const KeyFrame& kf) { return kf.connections_; }
  static const std::vector<int>& ordered_weights(const KeyFrame& kf) { return kf.ordered_weights_; }
  static bool first_connection(const KeyFrame& kf) { return kf.first_connection_; }
  static void restore(KeyFrame& kf, KeyFrame* parent, std::vector<KeyFrame*> loop_edges,
                      std::vector<std::pair<KeyFrame*, int>> connections, std::vector<KeyFrame*> ordered,
                      std::vector<int> ordered_weights, bool first_connection, bool not_erase, bool origin) {
    kf.parent_ = parent;
    kf.loop_edges_ = std::move(loop_edges);
    kf.connections_ = std::move(connections);
    kf.ordered_neighbours_ = std::move(ordered);
    kf.ordered_weights_ = std::move(ordered_weights);
    kf.first_connection_ = first_connection;
    kf.not_erase_ = not_erase;
    kf.origin_ = origin;
  }
  static void add_child(KeyFrame& kf, KeyFrame* child) { kf.children_.push_back(child); }

  static uint64_t next_keyframe_id(const Map& m) { return m.next_keyframe_id_; }
  static uint64_t next_map_point_id(const Map& m) { return m.next_map_point_id_; }
  static void set_counters(Map& m, uint64_t next_kf, uint64_t next_point, uint64_t origin) {
    m.next_keyframe_id_ = next_kf;
    m.next_map_point_id_ = next_point;
    m.origin_id_ = origin;
  }
  struct Removed {
    uint64_t id, parent_id;
    SE3d T_c_parent;
  };
  static std::vector<Removed> removed(const Map& m) {
    std::vector<Removed> out;
    for (const auto& [id, r] : m.removed_) out.push_back({id, r.parent_id, r.T_c_parent});
    std::sort(out.begin(), out.end(), [](const Removed& a, const Removed& b) { return a.id < b.id; });
    return out;
  }
};

namespace {

constexpr char kMagic[8] = {'A', 'G', 'V', 'S', 'M', 'A', 'P', '\0'};
constexpr uint64_t kNone = std::numeric_limits<uint64_t>::max();
constexpr uint64_t kRetired = kNone - 1;  // a keypoint that saw a retired map point

uint32_t crc32_of(const void* data, std::size_t size) {
  uLong crc = crc32(0L, Z_NULL, 0);
  const auto* p = static_cast<const Bytef*>(data);
  while (size > 0) {
    const uInt n = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = crc32(crc, p, n);
    p += n;
    size -= n;
  }
  return static_cast<uint32_t>(crc);
}

std::string hex(uint64_t v, int digits) {
  char buf[32];
  std::snprintf(buf, sizeof(buf), "%0*llx", digits, static_cast<unsigned long long>(v));
  return buf;
}

class Writer {
 public:
  explicit Writer(std::string& out) : out_(out) {}
  template <typename T>
  void put(const T& v) {
    static_assert(std::is_trivially_copyable_v<T>);
    const auto* p = reinterpret_cast<const char*>(&v);
    out_.append(p, sizeof(T));
  }
  void bytes(const void* data, std::size_t n) { out_.append(static_cast<const char*>(data), n); }
  void pose(const SE3d& T) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) put<double>(T.matrix()(r, c));
    }
  }

 private:
  std::string& out_;
};

class Reader {
 public:
  Reader(const std::string& data, std::size_t offset, const std::string& source)
      : data_(data), pos_(offset), source_(source) {}
  template <typename T>
  T get(const char* field) {
    static_assert(std::is_trivially_copyable_v<T>);
    need(sizeof(T), field);
    T v;
    std::memcpy(&v, data_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  void bytes(void* out, std::size_t n, const char* field) {
    need(n, field);
    if (n == 0) return;  // out may be an empty vector's null data(), which memcpy must not get
    std::memcpy(out, data_.data() + pos_, n);
    pos_ += n;
  }
  SE3d pose(const char* field) {
    Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c) M(r, c) = get<double>(field);
    }
    SE3d T;
    T.matrix() = M;
    if (!M.allFinite() || !is_valid_pose(T)) throw InputError(source_, field, "expected a rigid transform (3x4)");
    return T;
  }
  // A count that must fit in the remaining bytes at `min_item_bytes` each.
  uint32_t count(const char* field, std::size_t min_item_bytes) {
    const uint32_t n = get<uint32_t>(field);
    if (min_item_bytes > 0 && static_cast<std::size_t>(n) > (data_.size() - pos_) / min_item_bytes) {
      throw InputError(source_, field, "expected a count that fits the file (read " + std::to_string(n) + ")");
    }
    return n;
  }
  std::size_t position() const { return pos_; }
  bool at_end() const { return pos_ == data_.size(); }

 private:
  void need(std::size_t n, const char* field) const {
    if (data_.size() - pos_ < n) {
      throw InputError(source_, field,
                       "expected " + std::to_string(n) + " more bytes at offset " + std::to_string(pos_) +
                           " (the payload ends early)");
    }
  }
  const std::string& data_;
  std::size_t pos_;
  const std::string& source_;
};

}  // namespace

MapFileContext MapFileContext::from(const FrameGeometry& g, uint64_t vocabulary_id, int direct_index_level) {
  MapFileContext c;
  c.fx = g.camera.fx;
  c.fy = g.camera.fy;
  c.cx = g.camera.cx;
  c.cy = g.camera.cy;
  c.baseline_m = g.baseline_m;
  c.width = g.camera.width;
  c.height = g.camera.height;
  c.n_levels = g.n_levels;
  c.scale_factor = g.scale_factor;
  c.vocabulary_id = vocabulary_id;
  c.direct_index_level = vocabulary_id != 0 ? direct_index_level : 0;
  return c;
}

std::string MapFileContext::describe() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf), "%dx%d fx %.3f fy %.3f cx %.3f cy %.3f baseline %.4f m, %d levels x %.3f", width,
                height, fx, fy, cx, cy, baseline_m, n_levels, scale_factor);
  return buf;
}

std::string encode_map(const Map& map, const MapFileContext& context) {
  std::vector<KeyFramePtr> kfs = map.keyframes();
  kfs.erase(std::remove_if(kfs.begin(), kfs.end(), [](const KeyFramePtr& k) { return k->bad(); }), kfs.end());
  std::unordered_set<const KeyFrame*> saved_kfs;
  for (const KeyFramePtr& k : kfs) saved_kfs.insert(k.get());
  // Only links that both sides record are saved (a keyframe may list a point at a keypoint that the point does not
  // record, e.g. after a fusion that found the point already observed there): the file is always consistent.
  auto observation_ok = [&](const MapPoint& p, const Observation& o) {
    return saved_kfs.count(o.keyframe) && o.index >= 0 && static_cast<std::size_t>(o.index) < o.keyframe->size() &&
           o.keyframe->map_point(static_cast<std::size_t>(o.index)).get() == &p;
  };
  std::vector<MapPointPtr> points;
  for (const MapPointPtr& p : map.map_points()) {
    if (p->bad()) continue;
    for (const Observation& o : p->observations()) {
      if (observation_ok(*p, o)) {
        points.push_back(p);
        break;
      }
    }
  }
  std::unordered_set<const MapPoint*> saved_points;
  for (const MapPointPtr& p : points) saved_points.insert(p.get());
  auto saved_kf = [&](const KeyFrame* k) { return k && saved_kfs.count(k) ? k->id : kNone; };
  std::size_t estimate = kMapHeaderBytes + 256;
  for (const KeyFramePtr& kf : kfs) estimate += 256 + kf->size() * 80;
  for (const MapPointPtr& p : points) estimate += 160 + p->observations().size() * 12;
  std::string out;
  out.reserve(estimate);
  out.resize(kMapHeaderBytes, '\0');
  Writer w(out);
  w.put<double>(context.fx);
  w.put<double>(context.fy);
  w.put<double>(context.cx);
  w.put<double>(context.cy);
  w.put<double>(context.baseline_m);
  w.put<int32_t>(context.width);
  w.put<int32_t>(context.height);
  w.put<int32_t>(context.n_levels);
  w.put<double>(context.scale_factor);
  w.put<uint64_t>(MapFileAccess::next_keyframe_id(map));
  w.put<uint64_t>(MapFileAccess::next_map_point_id(map));
  w.put<uint64_t>(map.origin_keyframe_id());

  for (const KeyFramePtr& kf : kfs) {
    w.put<uint64_t>(kf->id);
    w.put<uint64_t>(kf->frame_id);
    w.put<int64_t>(kf->t_ns);
    w.pose(kf->T_c_w());
    const std::size_t n = kf->size();
    w.put<uint32_t>(static_cast<uint32_t>(n));
    for (const cv::KeyPoint& kp : kf->keypoints) {
      w.put<float>(kp.pt.x);
      w.put<float>(kp.pt.y);
      w.put<float>(kp.size);
      w.put<float>(kp.angle);
      w.put<float>(kp.response);
      w.put<int32_t>(kp.octave);
      w.put<int32_t>(kp.class_id);
    }
    for (std::size_t i = 0; i < n; ++i) w.bytes(kf->descriptor(i), 32);
    w.bytes(kf->u_right.data(), n * sizeof(float));
    w.bytes(kf->depth.data(), n * sizeof(float));
    for (std::size_t i = 0; i < n; ++i) {
      const MapPointPtr& p = kf->map_point(i);
      const bool linked = p && saved_points.count(p.get()) && p->index_in(kf.get()) == static_cast<int>(i);
      w.put<uint64_t>(linked ? p->id : kf->keypoint_retired(i) ? kRetired : kNone);
    }
    w.put<uint64_t>(saved_kf(kf->parent()));
    uint8_t flags = 0;
    if (kf->is_origin()) flags |= 1;
    if (kf->not_erase()) flags |= 2;
    if (MapFileAccess::first_connection(*kf)) flags |= 4;
    w.put<uint8_t>(flags);
    std::vector<uint64_t> loops;
    for (const KeyFrame* l : kf->loop_edges()) {
      if (saved_kfs.count(l)) loops.push_back(l->id);
    }
    w.put<uint32_t>(static_cast<uint32_t>(loops.size()));
    for (const uint64_t id : loops) w.put<uint64_t>(id);
    std::vector<std::pair<uint64_t, int32_t>> links;
    for (const auto& [other, weight] : MapFileAccess::connections(*kf)) {
      if (saved_kfs.count(other)) links.emplace_back(other->id, weight);
    }
    w.put<uint32_t>(static_cast<uint32_t>(links.size()));
    for (const auto& [id, weight] : links) {
      w.put<uint64_t>(id);
      w.put<int32_t>(weight);
    }
    links.clear();
    const auto& ordered = kf->covisibles();
    const auto& weights = MapFileAccess::ordered_weights(*kf);
    for (std::size_t k = 0; k < ordered.size(); ++k) {
      if (saved_kfs.count(ordered[k])) links.emplace_back(ordered[k]->id, weights[k]);
    }
    w.put<uint32_t>(static_cast<uint32_t>(links.size()));
    for (const auto& [id, weight] : links) {
      w.put<uint64_t>(id);
      w.put<int32_t>(weight);
    }
  }

  for (const MapPointPtr& p : points) {
    w.put<uint64_t>(p->id);
    w.put<uint64_t>(p->first_keyframe_id);
    w.put<uint64_t>(p->first_frame_id);
    for (int k = 0; k < 3; ++k) w.put<double>(p->p_w[k]);
    for (int k = 0; k < 3; ++k) w.put<double>(p->normal_w[k]);
    w.bytes(p->descriptor.data(), 32);
    w.put<float>(p->min_distance_m);
    w.put<float>(p->max_distance_m);
    std::vector<const Observation*> obs;
    for (const Observation& o : p->observations()) {
      if (observation_ok(*p, o)) obs.push_back(&o);
    }
    uint64_t ref = saved_kf(p->reference_keyframe);
    if (ref == kNone) ref = obs.front()->keyframe->id;
    w.put<uint64_t>(ref);
    w.put<int32_t>(p->visible);
    w.put<int32_t>(p->found);
    w.put<uint32_t>(static_cast<uint32_t>(obs.size()));
    for (const Observation* o : obs) {
      w.put<uint64_t>(o->keyframe->id);
      w.put<int32_t>(o->index);
    }
  }

  const auto removed = MapFileAccess::removed(map);
  w.put<uint32_t>(static_cast<uint32_t>(removed.size()));
  for (const auto& r : removed) {
    w.put<uint64_t>(r.id);
    w.put<uint64_t>(r.parent_id);
    w.pose(r.T_c_parent);
  }

  // Header.
  const uint64_t payload = out.size() - kMapHeaderBytes;
  char* h = out.data();
  std::memcpy(h, kMagic, 8);
  const uint32_t version = kMapFormatVersion, header_size = kMapHeaderBytes, flags = 0;
  const uint32_t payload_crc = crc32_of(out.data() + kMapHeaderBytes, payload);
  const uint64_t n_kfs = kfs.size(), n_points = points.size();
  const uint32_t level = static_cast<uint32_t>(context.direct_index_level);
  std::memcpy(h + 8, &version, 4);
  std::memcpy(h + 12, &header_size, 4);
  std::memcpy(h + 16, &payload, 8);
  std::memcpy(h + 24, &payload_crc, 4);
  std::memcpy(h + 28, &flags, 4);
  std::memcpy(h + 32, &context.vocabulary_id, 8);
  std::memcpy(h + 40, &n_kfs, 8);
  std::memcpy(h + 48, &n_points, 8);
  std::memcpy(h + 56, &level, 4);
  const uint32_t header_crc = crc32_of(h, 60);
  std::memcpy(h + 60, &header_crc, 4);
  return out;
}

MapFileSummary check_map_file(const std::string& bytes, const std::string& source) {
  MapFileSummary s;
  if (bytes.size() < kMapHeaderBytes) {
    throw InputError(source, "header",
                     "expected at least the " + std::to_string(kMapHeaderBytes) +
                         "-byte header of an agvslam map file; the file has " + std::to_string(bytes.size()) +
                         " bytes (truncated?)");
  }
  const char* h = bytes.data();
  if (std::memcmp(h, kMagic, 8) != 0) {
    throw InputError(source, "magic", "expected an agvslam map file (starting with \"AGVSMAP\")");
  }
  uint32_t header_crc = 0;
  std::memcpy(&header_crc, h + 60, 4);
  const uint32_t computed_header_crc = crc32_of(h, 60);
  if (header_crc != computed_header_crc) {
    throw InputError(source, "header",
                     "expected header checksum " + hex(header_crc, 8) + ", computed " + hex(computed_header_crc, 8) +
                         " (corrupt file)");
  }
  uint32_t header_size = 0;
  std::memcpy(&s.version, h + 8, 4);
  std::memcpy(&header_size, h + 12, 4);
  if (s.version < kMapFormatOldestReadable || s.version > kMapFormatVersion) {
    throw InputError(source, "version",
                     "expected map format version " + std::to_string(kMapFormatOldestReadable) + " to " +
                         std::to_string(kMapFormatVersion) + ", the file has version " + std::to_string(s.version));
  }
  if (header_size != kMapHeaderBytes) {
    throw InputError(source, "header size",
                     "expected " + std::to_string(kMapHeaderBytes) + ", read " + std::to_string(header_size));
  }
  std::memcpy(&s.payload_bytes, h + 16, 8);
  std::memcpy(&s.payload_crc32, h + 24, 4);
  std::memcpy(&s.vocabulary_id, h + 32, 8);
  std::memcpy(&s.keyframes, h + 40, 8);
  std::memcpy(&s.map_points, h + 48, 8);
  uint32_t level = 0;
  std::memcpy(&level, h + 56, 4);
  s.direct_index_level = static_cast<int>(level);
  const uint64_t actual = bytes.size() - kMapHeaderBytes;
  if (actual != s.payload_bytes) {
    throw InputError(source, "payload",
                     "expected " + std::to_string(s.payload_bytes) + " bytes after the header, the file has " +
                         std::to_string(actual) + (actual < s.payload_bytes ? " (truncated)" : " (trailing bytes)"));
  }
  const uint32_t crc = crc32_of(bytes.data() + kMapHeaderBytes, actual);
  if (crc != s.payload_crc32) {
    throw InputError(source, "payload",
                     "expected CRC-32 " + hex(s.payload_crc32, 8) + ", computed " + hex(crc, 8) + " (corrupt file)");
  }
  return s;
}

MapFileSummary decode_map(const std::string& bytes, const std::string& source, const MapFileContext& expected,
                          const FrameGeometryPtr& geometry, Map& map) {
  const MapFileSummary s = check_map_file(bytes, source);
  if (s.vocabulary_id != expected.vocabulary_id) {
    throw InputError(source, "vocabulary",
                     "expected a map built with vocabulary " + hex(expected.vocabulary_id, 16) +
                         (expected.vocabulary_id == 0 ? " (none loaded)" : "") + "; this map was built with " +
                         hex(s.vocabulary_id, 16) + (s.vocabulary_id == 0 ? " (none)" : ""));
  }
  if (s.vocabulary_id != 0 && s.direct_index_level != expected.direct_index_level) {
    throw InputError(source, "direct index level",
                     "expected " + std::to_string(expected.direct_index_level) + " (params/place.yaml), the map has " +
                         std::to_string(s.direct_index_level));
  }
  Reader r(bytes, kMapHeaderBytes, source);
  MapFileContext c;
  c.fx = r.get<double>("camera");
  c.fy = r.get<double>("camera");
  c.cx = r.get<double>("camera");
  c.cy = r.get<double>("camera");
  c.baseline_m = r.get<double>("camera");
  c.width = r.get<int32_t>("camera");
  c.height = r.get<int32_t>("camera");
  c.n_levels = r.get<int32_t>("camera");
  c.scale_factor = r.get<double>("camera");
  auto close = [](double a, double b) { return std::fabs(a - b) <= 1e-6 * std::max(1.0, std::fabs(b)); };
  if (!close(c.fx, expected.fx) || !close(c.fy, expected.fy) || !close(c.cx, expected.cx) ||
      !close(c.cy, expected.cy) || !close(c.baseline_m, expected.baseline_m) || c.width != expected.width ||
      c.height != expected.height || c.n_levels != expected.n_levels || !close(c.scale_factor, expected.scale_factor)) {
    throw InputError(source, "camera",
                     "expected a map made with this camera and ORB pyramid (" + expected.describe() +
                         "); the map has " + c.describe());
  }
  const uint64_t next_kf = r.get<uint64_t>("counters");
  const uint64_t next_point = r.get<uint64_t>("counters");
  const uint64_t origin = r.get<uint64_t>("counters");

  // Everything is read into a private map; errors leave the caller's map empty. (`links` owns the keyframes
  // until they join `loaded`: declared first, so it outlives `loaded`, whose points point back at them.)
  struct KeyframeLinks {
    KeyFramePtr kf;
    std::vector<uint64_t> point_ids;
    uint64_t parent = kNone;
    uint8_t flags = 0;
    std::vector<uint64_t> loop_edges;
    std::vector<std::pair<uint64_t, int>> connections, ordered;
  };
  std::vector<KeyframeLinks> links;
  Map loaded;
  links.reserve(static_cast<std::size_t>(std::min<uint64_t>(s.keyframes, 1u << 20)));
  std::unordered_map<uint64_t, KeyFrame*> kf_by_id;
  Frame frame;
  std::vector<cv::KeyPoint> kps;
  std::vector<float> u_right, depth;
  cv::Mat descs;
  for (uint64_t k = 0; k < s.keyframes; ++k) {
    KeyframeLinks l;
    const uint64_t id = r.get<uint64_t>("keyframe");
    const std::string where = "keyframe " + std::to_string(id);
    const uint64_t frame_id = r.get<uint64_t>(where.c_str());
    const int64_t t_ns = r.get<int64_t>(where.c_str());
    const SE3d T_c_w = r.pose(where.c_str());
    const uint32_t n = r.count(where.c_str(), 28 + 32 + 8 + 8);
    kps.resize(n);
    for (uint32_t i = 0; i < n; ++i) {
      cv::KeyPoint& kp = kps[i];
      kp.pt.x = r.get<float>(where.c_str());
      kp.pt.y = r.get<float>(where.c_str());
      kp.size = r.get<float>(where.c_str());
      kp.angle = r.get<float>(where.c_str());
      kp.response = r.get<float>(where.c_str());
      kp.octave = r.get<int32_t>(where.c_str());
      kp.class_id = r.get<int32_t>(where.c_str());
      // Inside the image (ORB finds keypoints there): the feature grid turns the position into a cell index.
      const bool inside = kp.pt.x >= 0 && kp.pt.x <= static_cast<float>(geometry->camera.width) && kp.pt.y >= 0 &&
                          kp.pt.y <= static_cast<float>(geometry->camera.height);
      if (kp.octave < 0 || kp.octave >= geometry->n_levels || !inside) {
        throw InputError(source, where + " keypoint " + std::to_string(i),
                         "expected a position inside the " + std::to_string(geometry->camera.width) + "x" +
                             std::to_string(geometry->camera.height) + " image and a pyramid level in [0, " +
                             std::to_string(geometry->n_levels - 1) + "]");
      }
    }
    descs.create(static_cast<int>(n), 32, CV_8UC1);
    if (n > 0) r.bytes(descs.data, std::size_t(n) * 32, where.c_str());
    u_right.resize(n);
    depth.resize(n);
    r.bytes(u_right.data(), n * sizeof(float), where.c_str());
    r.bytes(depth.data(), n * sizeof(float), where.c_str());
    l.point_ids.resize(n);
    r.bytes(l.point_ids.data(), n * sizeof(uint64_t), where.c_str());
    l.parent = r.get<uint64_t>(where.c_str());
    l.flags = r.get<uint8_t>(where.c_str());
    const uint32_t n_loops = r.count(where.c_str(), 8);
    for (uint32_t i = 0; i < n_loops; ++i) l.loop_edges.push_back(r.get<uint64_t>(where.c_str()));
    const uint32_t n_conn = r.count(where.c_str(), 12);
    for (uint32_t i = 0; i < n_conn; ++i) {
      const uint64_t other = r.get<uint64_t>(where.c_str());
      l.connections.emplace_back(other, r.get<int32_t>(where.c_str()));
    }
    const uint32_t n_ordered = r.count(where.c_str(), 12);
    for (uint32_t i = 0; i < n_ordered; ++i) {
      const uint64_t other = r.get<uint64_t>(where.c_str());
      l.ordered.emplace_back(other, r.get<int32_t>(where.c_str()));
    }
    if (kf_by_id.count(id) || id >= next_kf) {
      throw InputError(source, where, "expected a unique keyframe id below the next id " + std::to_string(next_kf));
    }
    frame.assign(frame_id, t_ns, geometry, kps, descs, u_right, depth);
    frame.set_pose(T_c_w);
    l.kf = std::make_shared<KeyFrame>(id, frame);
    kf_by_id[id] = l.kf.get();
    links.push_back(std::move(l));
  }
  if (s.keyframes > 0 && !kf_by_id.count(origin)) {
    throw InputError(source, "counters", "expected the origin keyframe " + std::to_string(origin) + " in the map");
  }
  auto keyframe_of = [&](uint64_t id, const std::string& where) {
    const auto it = kf_by_id.find(id);
    if (it == kf_by_id.end())
      throw InputError(source, where, "expected the id of a saved keyframe, read " + std::to_string(id));
    return it->second;
  };

  std::unordered_map<uint64_t, MapPointPtr> point_by_id;
  for (uint64_t k = 0; k < s.map_points; ++k) {
    const uint64_t id = r.get<uint64_t>("map point");
    const std::string where = "map point " + std::to_string(id);
    const uint64_t first_kf = r.get<uint64_t>(where.c_str());
    const uint64_t first_frame = r.get<uint64_t>(where.c_str());
    Eigen::Vector3d p, normal;
    for (int c2 = 0; c2 < 3; ++c2) p[c2] = r.get<double>(where.c_str());
    for (int c2 = 0; c2 < 3; ++c2) normal[c2] = r.get<double>(where.c_str());
    if (!p.allFinite() || !normal.allFinite()) throw InputError(source, where, "expected a finite position and normal");
    if (point_by_id.count(id) || id >= next_point) {
      throw InputError(source, where, "expected a unique map point id below the next id " + std::to_string(next_point));
    }
    auto point = std::make_shared<MapPoint>(id, p, first_kf, first_frame);
    point->normal_w = normal;
    r.bytes(point->descriptor.data(), 32, where.c_str());
    point->min_distance_m = r.get<float>(where.c_str());
    point->max_distance_m = r.get<float>(where.c_str());
    const uint64_t ref = r.get<uint64_t>(where.c_str());
    point->visible = r.get<int32_t>(where.c_str());
    point->found = r.get<int32_t>(where.c_str());
    const uint32_t n_obs = r.count(where.c_str(), 12);
    for (uint32_t i = 0; i < n_obs; ++i) {
      KeyFrame* kf = keyframe_of(r.get<uint64_t>(where.c_str()), where);
      const int32_t index = r.get<int32_t>(where.c_str());
      if (index < 0 || static_cast<std::size_t>(index) >= kf->size() || point->is_in(kf)) {
        throw InputError(source, where,
                         "expected one observation per keyframe at a keypoint index below " +
                             std::to_string(kf->size()) + " (keyframe " + std::to_string(kf->id) + ")");
      }
      point->add_observation(kf, index);
    }
    point->reference_keyframe = ref == kNone ? nullptr : keyframe_of(ref, where);
    point_by_id[id] = point;
    loaded.add_map_point(point);
  }

  // Keyframe links.
  for (KeyframeLinks& l : links) {
    KeyFrame& kf = *l.kf;
    const std::string where = "keyframe " + std::to_string(kf.id);
    for (std::size_t i = 0; i < l.point_ids.size(); ++i) {
      if (l.point_ids[i] == kNone) continue;
      if (l.point_ids[i] == kRetired) {
        kf.retire_keypoint(i);
        continue;
      }
      const auto it = point_by_id.find(l.point_ids[i]);
      if (it == point_by_id.end() || it->second->index_in(&kf) != static_cast<int>(i)) {
        throw InputError(source, where + " keypoint " + std::to_string(i),
                         "expected a saved map point that records this observation (map point " +
                             std::to_string(l.point_ids[i]) + ")");
      }
      kf.add_map_point(it->second, i);
    }
    KeyFrame* parent = l.parent == kNone ? nullptr : keyframe_of(l.parent, where);
    std::vector<KeyFrame*> loops;
    for (uint64_t id : l.loop_edges) loops.push_back(keyframe_of(id, where));
    std::vector<std::pair<KeyFrame*, int>> connections;
    for (const auto& [id, w] : l.connections) connections.emplace_back(keyframe_of(id, where), w);
    std::vector<KeyFrame*> ordered;
    std::vector<int> weights;
    for (const auto& [id, w] : l.ordered) {
      ordered.push_back(keyframe_of(id, where));
      weights.push_back(w);
    }
    MapFileAccess::restore(kf, parent, std::move(loops), std::move(connections), std::move(ordered), std::move(weights),
                           (l.flags & 4) != 0, (l.flags & 2) != 0, (l.flags & 1) != 0);
  }
  // Every point observation must be mirrored by its keyframe.
  for (const auto& [id, p] : point_by_id) {
    for (const Observation& o : p->observations()) {
      if (o.keyframe->map_point(static_cast<std::size_t>(o.index)) != p) {
        throw InputError(source, "map point " + std::to_string(id),
                         "expected keyframe " + std::to_string(o.keyframe->id) + " to list it at keypoint " +
                             std::to_string(o.index));
      }
    }
  }
  // Children follow from the parents, in id order (as the tree grew).
  for (KeyframeLinks& l : links) {
    if (l.kf->parent()) MapFileAccess::add_child(*l.kf->parent(), l.kf.get());
  }
  const uint32_t n_removed = r.count("removed keyframes", 16 + 96);
  std::vector<MapFileAccess::Removed> removed;
  for (uint32_t i = 0; i < n_removed; ++i) {
    const uint64_t id = r.get<uint64_t>("removed keyframes");
    const uint64_t parent = r.get<uint64_t>("removed keyframes");
    removed.push_back({id, parent, r.pose("removed keyframes")});
  }
  if (!r.at_end()) {
    throw InputError(
        source, "payload",
        "expected the payload to end after the removed keyframes (offset " + std::to_string(r.position()) + ")");
  }
  // The origin first (Map::add_keyframe marks the first keyframe added when it has no origin yet).
  MapFileAccess::set_counters(loaded, next_kf, next_point, s.keyframes > 0 ? origin : UINT64_MAX);
  for (KeyframeLinks& l : links) loaded.add_keyframe(l.kf);
  for (const auto& rm : removed) loaded.record_removed_keyframe(rm.id, rm.parent_id, rm.T_c_parent);
  links.clear();
  map.take_from(loaded);
  return s;
}

void save_map_file(const std::string& path, const std::string& bytes, const MapWriteHooks& hooks) {
  namespace fs = std::filesystem;
  fs::path parent = fs::path(path).parent_path();
  if (parent.empty()) parent = ".";
  std::error_code ec;
  if (!fs::is_directory(parent, ec)) {
    throw InputError(path, "", "expected an existing folder " + parent.string() + " to save the map in");
  }
  const std::string tmp = path + ".tmp";
  auto stage = [&](const char* name, std::size_t written) {
    if (hooks.on_stage) hooks.on_stage(name, written);
  };
  auto fail = [&](const std::string& what, int fd) {
    const std::string reason = what + ": " + std::strerror(errno);
    if (fd >= 0) ::close(fd);
    ::unlink(tmp.c_str());
    throw InputError(path, "", "cannot save the map (" + reason + "); the previous file is unchanged");
  };
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) fail("open " + tmp, -1);
  stage("open", 0);
  const std::size_t chunk = std::max<std::size_t>(1, hooks.chunk_bytes);
  std::size_t written = 0;
  std::size_t next_report = chunk;
  while (written < bytes.size()) {
    const std::size_t n_want = std::min(bytes.size() - written, next_report - written);
    const ssize_t n = ::write(fd, bytes.data() + written, n_want);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail("write " + tmp, fd);
    }
    written += static_cast<std::size_t>(n);
    if (written == next_report && written < bytes.size()) {
      stage("chunk", written);
      next_report += chunk;
    }
  }
  stage("written", written);
  if (::fsync(fd) != 0) fail("fsync " + tmp, fd);
  stage("fsync", written);
  if (::close(fd) != 0) fail("close " + tmp, -1);
  if (::rename(tmp.c_str(), path.c_str()) != 0) fail("rename " + tmp, -1);
  stage("renamed", written);
  const int dir_fd = ::open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);  // makes the rename durable; the new file is complete either way
    ::close(dir_fd);
  }
  stage("done", written);
}

std::string read_map_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "expected a readable map file (" + std::string(std::strerror(errno)) + ")");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path, "", "expected a readable map file (read error)");
  return bytes;
}

}  // namespace agvslam::slam
