#pragma once
// The params file reader under its old name, for src/dynamic/dynamic_config.cpp only: it goes when dynamic's loader
// is converted to a params::Table (agvslam/core/param_table.h), like every other loader.

#include "agvslam/core/params_file.h"

namespace agvslam::stereo {

using ParamsReader = params::File;

}  // namespace agvslam::stereo
