#include "agvslam/core/error.h"

#include <utility>

namespace agvslam {
namespace {
std::string compose(const std::string& source, const std::string& where, const std::string& expected) {
  std::string msg = source;
  if (!where.empty()) msg += ": " + where;
  msg += ": " + expected;
  return msg;
}
}  // namespace

InputError::InputError(std::string source, std::string where, std::string expected)
    : std::runtime_error(compose(source, where, expected)),
      source_(std::move(source)),
      where_(std::move(where)),
      expected_(std::move(expected)) {}

}  // namespace agvslam
