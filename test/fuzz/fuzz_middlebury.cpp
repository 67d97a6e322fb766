// Middlebury scene files: PFM disparity maps (parsePfm) and calib.txt (parseMiddleburyCalibration),
// src/sensors/middlebury_folder.cpp. The first byte picks the parser, the rest is the file. Any
// file must be rejected with std::runtime_error or give an image whose size matches its values,
// or a calibration whose camera() is valid.
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_input.h"
#include "occupancy_fusion/sensors/middlebury_folder.h"

namespace occupancy_fusion {
namespace fuzz {

void writeSeeds() {
  // 3 x 2 little-endian Pf with one unknown (inf) value.
  std::string pfm = "Pf\n3 2\n-1.0\n";
  const float values[6] = {1.5f, 2.0f, INFINITY, 4.25f, 0.0f, 8.0f};
  pfm.append(reinterpret_cast<const char*>(values), sizeof(values));
  std::vector<std::uint8_t> seed(1, 0);
  seed.insert(seed.end(), pfm.begin(), pfm.end());
  writeSeed("seed_pfm", seed);
  const std::string calib =
      "cam0=[100 0 10.5; 0 100 8.5; 0 0 1]\ncam1=[100 0 12.5; 0 100 8.5; 0 0 1]\n"
      "doffs=2\nbaseline=120.5\nwidth=3\nheight=2\nndisp=16\nvmin=1\nvmax=9\n";
  seed.assign(1, 1);
  seed.insert(seed.end(), calib.begin(), calib.end());
  writeSeed("seed_calib", seed);
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  if (size == 0) return 0;
  const std::string file(reinterpret_cast<const char*>(data) + 1, size - 1);
  try {
    if (data[0] % 2 == 0) {
      const PfmImage image = parsePfm(file);
      if (image.values.size() !=
          static_cast<std::size_t>(image.width) * image.height * image.channels) {
        std::abort();
      }
    } else {
      const MiddleburyCalibration calibration = parseMiddleburyCalibration(file);
      calibration.camera();  // throws std::invalid_argument when not a valid camera
    }
  } catch (const std::runtime_error&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
