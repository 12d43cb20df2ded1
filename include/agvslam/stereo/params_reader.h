#pragma once
// Reads a params/*.yaml file section by section. Every error is an InputError naming the file, the field
// ("section.key") and what was expected, e.g.
//   "params/dynamic.yaml: epipolar.a_epi_px: expected a number (pixels)"
// Used by the stereo and dynamic configuration loaders; yaml-cpp stays an implementation detail.

#include <initializer_list>
#include <memory>
#include <string>

namespace agvslam::stereo {

class ParamsReader {
 public:
  // Loads the file. Throws InputError for a missing or unreadable file, a YAML syntax error, or a top level
  // that is not a map.
  explicit ParamsReader(const std::string& path);
  ~ParamsReader();
  ParamsReader(const ParamsReader&) = delete;
  ParamsReader& operator=(const ParamsReader&) = delete;

  const std::string& path() const;
  bool has_section(const std::string& section) const;

  // Throws InputError for a top-level key (or a key inside `section`) that is not in `allowed`.
  void check_sections(std::initializer_list<const char*> allowed) const;
  void check_keys(const std::string& section, std::initializer_list<const char*> allowed) const;

  // Overwrites `value` with section.key when present; leaves it unchanged when absent. A value of the wrong
  // type raises InputError(path, "section.key", "expected " + expectation).
  void read(const std::string& section, const std::string& key, int& value, const char* expectation) const;
  void read(const std::string& section, const std::string& key, double& value, const char* expectation) const;
  void read(const std::string& section, const std::string& key, bool& value, const char* expectation) const;
  void read(const std::string& section, const std::string& key, std::string& value, const char* expectation) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace agvslam::stereo
