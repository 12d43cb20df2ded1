#include "agvslam/stereo/params_reader.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>

#include "agvslam/core/error.h"

namespace agvslam::stereo {

struct ParamsReader::Impl {
  std::string path;
  YAML::Node root;
};

namespace {

std::string join(std::initializer_list<const char*> names) {
  std::string list;
  for (const char* n : names) list += (list.empty() ? "" : ", ") + std::string(n);
  return list;
}

bool contains(std::initializer_list<const char*> names, const std::string& key) {
  for (const char* n : names) {
    if (key == n) return true;
  }
  return false;
}

template <typename T>
void read_scalar(const YAML::Node& root, const std::string& path, const std::string& section, const std::string& key,
                 T& value, const char* expectation) {
  const YAML::Node sec = root[section];
  if (!sec || !sec.IsMap()) return;
  const YAML::Node node = sec[key];
  if (!node) return;
  if (!node.IsScalar()) throw InputError(path, section + "." + key, std::string("expected ") + expectation);
  try {
    value = node.as<T>();
  } catch (const YAML::Exception&) {
    throw InputError(path, section + "." + key, std::string("expected ") + expectation);
  }
}

}  // namespace

ParamsReader::ParamsReader(const std::string& path) : impl_(std::make_unique<Impl>()) {
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

ParamsReader::~ParamsReader() = default;

const std::string& ParamsReader::path() const { return impl_->path; }

bool ParamsReader::has_section(const std::string& section) const {
  return impl_->root && impl_->root.IsMap() && impl_->root[section];
}

void ParamsReader::check_sections(std::initializer_list<const char*> allowed) const {
  if (!impl_->root || !impl_->root.IsMap()) return;
  for (const auto& kv : impl_->root) {
    const std::string key = kv.first.as<std::string>();
    if (!contains(allowed, key)) {
      throw InputError(impl_->path, key, "unknown section; expected one of: " + join(allowed));
    }
  }
}

void ParamsReader::check_keys(const std::string& section, std::initializer_list<const char*> allowed) const {
  if (!has_section(section)) return;
  const YAML::Node sec = impl_->root[section];
  if (sec.IsNull()) return;
  if (!sec.IsMap()) throw InputError(impl_->path, section, "expected a map of settings");
  for (const auto& kv : sec) {
    const std::string key = kv.first.as<std::string>();
    if (!contains(allowed, key)) {
      throw InputError(impl_->path, section + "." + key, "unknown setting; expected one of: " + join(allowed));
    }
  }
}

void ParamsReader::read(const std::string& section, const std::string& key, int& value,
                        const char* expectation) const {
  read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

void ParamsReader::read(const std::string& section, const std::string& key, double& value,
                        const char* expectation) const {
  read_scalar(impl_->root, impl_->path, section, key, value, expectation);
  if (!std::isfinite(value)) {
    throw InputError(impl_->path, section + "." + key, std::string("expected a finite ") + expectation);
  }
}

void ParamsReader::read(const std::string& section, const std::string& key, bool& value,
                        const char* expectation) const {
  read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

void ParamsReader::read(const std::string& section, const std::string& key, std::string& value,
                        const char* expectation) const {
  read_scalar(impl_->root, impl_->path, section, key, value, expectation);
}

}  // namespace agvslam::stereo
