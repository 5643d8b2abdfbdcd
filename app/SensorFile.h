#pragma once
// The sensor section of `ltmsim acquire --sensor FILE.yaml`: the camera and display model of
// acquire/Sensor.h, read strictly through scene/StrictYaml.h (the engine every data file is read
// with; acquire/ itself stays below scene/ and never sees YAML). Every key is optional; a missing
// one keeps acquire/Sensor.h's default (docs/acquisition.md lists them with their sources):
//
//   sensor:
//     seed: 1                    # noise streams (and the random patterns)
//     camera:
//       full_well: 10500         # electrons
//       exposure: 0.5            # fraction of the full well collected at radiance 1
//       read_noise: 2.4          # electrons rms
//       dark_level: 1.0          # mean dark electrons per exposure
//       bits: 12                 # 8, 10, 12 or 16
//     display:
//       contrast_ratio: 1000     # or black_level: 0.001 (= 1 / contrast_ratio), not both
//       gamma: 2.2
//       bits: 8
//
// Bad input is an InputError "FILE:LINE:COLUMN: sensor.camera.read_noise: must be >= 0 (got -1)".
#include <string>

#include "acquire/Sensor.h"

namespace ltm::app {

acquire::SensorModel load_sensor_file(const std::string& path);

}  // namespace ltm::app
