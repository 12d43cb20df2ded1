// params/*.yaml and the daemon's YAML as the loaders read them through their tables (core's params::File and
// params::Table): every section of the tables this build links (place's vocabulary, the daemon's can,
// can_odometry and dds), read and validated when present.
#include "agvslam/core/param_table.h"
#include "agvslam/core/params_file.h"
#include "agvslam/drivers/can/can_config.h"
#include "agvslam/drivers/can/odometry_input.h"
#include "agvslam/drivers/dds/dds_config.h"
#include "agvslam/place/place_config.h"
#include "fuzz_common.h"

namespace {

template <class C>
void read_section(const agvslam::params::File& file, const agvslam::params::Table<C>& table) {
  if (!file.has_section(table.section())) return;
  C config;
  table.read(file, config);
  table.validate(file.path(), config);
  table.describe(config);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string path = agvslam::fuzz::as_file(data, size, "params.yaml");
  agvslam::fuzz::expect_input_error_or_success([&] { agvslam::place::load_place_config(path); });
  agvslam::fuzz::expect_input_error_or_success([&] {
    const agvslam::params::File file(path);
    read_section(file, agvslam::drivers::can::can_params());
    read_section(file, agvslam::drivers::can::can_odometry_params());
    read_section(file, agvslam::drivers::dds::dds_params());
  });
  return 0;
}
