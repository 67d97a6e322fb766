// 7-Scenes text files: camera-intrinsics.txt (parseCameraMatrix) and frame-*.pose.txt
// (parsePoseMatrix), src/sensors/seven_scenes_folder.cpp. The same text goes to both. Any text
// must be rejected with an exception or give valid intrinsics and a finite rigid pose.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "fuzz_input.h"
#include "occupancy_fusion/sensors/seven_scenes_folder.h"

namespace occupancy_fusion {
namespace fuzz {

void writeSeeds() {
  const std::string intrinsics = "585 0 320\n0 585 240\n0 0 1\n";
  const std::string pose =
      " 9.9935108e-001 -1.3861383e-002 -3.3291239e-002 -2.1566930e-001\n"
      " 1.4200052e-002  9.9984968e-001  1.0070776e-002 -1.1463165e-001\n"
      " 3.3147849e-002 -1.0536674e-002  9.9939519e-001  2.3818785e-001\n"
      " 0.0000000e+000  0.0000000e+000  0.0000000e+000  1.0000000e+000\n";
  writeSeed("seed_intrinsics", std::vector<std::uint8_t>(intrinsics.begin(), intrinsics.end()));
  writeSeed("seed_pose", std::vector<std::uint8_t>(pose.begin(), pose.end()));
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    parseCameraMatrix(text, 640, 480).validate();
  } catch (const std::exception&) {
  }
  try {
    const Eigen::Isometry3d pose = parsePoseMatrix(text);
    const Eigen::Matrix3d rotation = pose.linear();
    // The mappers invert poses by transposing the rotation: it must be one.
    if (!pose.matrix().allFinite() ||
        !(rotation.transpose() * rotation).isApprox(Eigen::Matrix3d::Identity(), 1e-6) ||
        !(std::abs(rotation.determinant() - 1.0) < 1e-6)) {
      std::abort();
    }
  } catch (const std::runtime_error&) {
  }
  return 0;
}
