#include "agvslam/core/params_file.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "agvslam/core/error.h"

namespace agvslam::params {

struct File::Impl {
  std::string path;
  YAML::Node root;
};

namespace {

std::string join(const std::vector<std::string>& names) {
  std::string list;
  for (const std::string& n : names) list += (list.empty() ? "" : ", ") + n;
  return list;
}

bool contains(const std::vector<std::string>& names, const std::string& key) {
  return std::find(names.begin(), names.end(), key) != names.end();
}

// What a value that could not be converted looked like, for the message.
std::string shown(const YAML::Node& node) {
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a map";
  return "nothing";
}

// The node of section.key; an undefined node when the section or the key is absent (or the section is no map:
// check_keys reports that).
YAML::Node find(const YAML::Node& root, const std::string& section, const std::string& key) {
  const YAML::Node& const_root = root;
  if (!const_root.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  const YAML::Node sec = const_root[section];
  if (!sec || !sec.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  const YAML::Node& const_sec = sec;
  return const_sec[key];
}

template <typename T>
bool read_scalar(const YAML::Node& root, const std::string& path, const std::string& section, const std::string& key,
                 T& value, const std::string& expectation) {
  const YAML::Node node = find(root, section, key);
  if (!node) return false;
  const auto fail = [&] {
    throw InputError(path, section + "." + key, "expected " + expectation + ", got " + shown(node));
  };
  if (!node.IsScalar()) fail();
  T converted{};
  try {
    converted = node.as<T>();
  } catch (const YAML::Exception&) {
    fail();
  }
  if constexpr (std::is_floating_point_v<T>) {
    if (!std::isfinite(converted)) fail();
  }
  value = converted;
  return true;
}

// A YAML key may be a list or a map ("? [a, b]: 1"); a setting's name is always a plain word.
std::string key_name(const YAML::Node& key, const std::string& path, const std::string& where) {
  if (!key.IsScalar()) throw InputError(path, where, "expected a plain name as key, not a list or a map");
  return key.Scalar();
}

}  // namespace

File::File(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->path = path;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw InputError(path, "", "expected a readable YAML params file");
  try {
    impl_->root = YAML::LoadFile(path);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "line " + std::to_string(e.mark.line + 1), "expected valid YAML: " + e.msg);
  }
  if (impl_->root && !impl_->root.IsNull() && !impl_->root.IsMap()) {
    throw InputError(path, "(top level)", "expected a map of sections");
  }
}

File::~File() = default;

const std::string& File::path() const { return impl_->path; }

bool File::has_section(const std::string& section) const {
  const YAML::Node& root = impl_->root;
  return root.IsMap() && root[section];
}

void File::require_section(const std::string& section) const {
  if (!has_section(section)) throw InputError(impl_->path, section, "expected a '" + section + ":' section");
}

void File::check_sections(const std::vector<std::string>& allowed) const {
  if (!impl_->root.IsMap()) return;
  for (const auto& kv : impl_->root) {
    const std::string key = key_name(kv.first, impl_->path, "(top level)");
    if (!contains(allowed, key)) {
      throw InputError(impl_->path, key, "unknown section; expected one of: " + join(allowed));
    }
  }
}

void File::check_keys(const std::string& section, const std::vector<std::string>& allowed) const {
  if (!has_section(section)) return;
  const YAML::Node& root = impl_->root;
  const YAML::Node sec = root[section];
  if (sec.IsNull()) return;
  if (!sec.IsMap()) throw InputError(impl_->path, section, "expected a map of settings");
  for (const auto& kv : sec) {
    const std::string key = key_name(kv.first, impl_->path, section);
    if (!contains(allowed, key)) {
      throw InputError(impl_->path, section + "." + key, "unknown setting; expected one of: " + join(allowed));
    }
  }
}

bool File::read(const std::string& section, const std::string& key, int& value, const std::string& expectation) const {
  return read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

bool File::read(const std::string& section, const std::string& key, double& value,
                const std::string& expectation) const {
  return read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

bool File::read(const std::string& section, const std::string& key, bool& value, const std::string& expectation) const {
  return read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

bool File::read(const std::string& section, const std::string& key, uint64_t& value,
                const std::string& expectation) const {
  return read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

bool File::read(const std::string& section, const std::string& key, std::string& value,
                const std::string& expectation) const {
  return read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

}  // namespace agvslam::params
