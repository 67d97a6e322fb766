// sensor_msgs/LaserScan -> the core's LaserScan (checkedLaserScan, src/sensors/laser_scan.cpp) and
// the REP-117 reading of each range (classifyBeam), as the laser mapper converts every scan. Any
// input must be rejected with std::invalid_argument or give a scan that passes validate(), with
// finite, non-decreasing beam angles and each hit within [range_min, range_max].
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <sensor_msgs/LaserScan.h>

#include "fuzz_input.h"
#include "occupancy_fusion/sensors/laser_scan.h"

namespace occupancy_fusion {
namespace fuzz {
namespace {

template <typename Codec>
void describe(Codec* codec, sensor_msgs::LaserScan* message, std::uint8_t* above_max_is_no_return) {
  codec->field(&message->angle_min);
  codec->field(&message->angle_max);
  codec->field(&message->angle_increment);
  codec->field(&message->range_min);
  codec->field(&message->range_max);
  codec->field(above_max_is_no_return);
  std::uint16_t count = static_cast<std::uint16_t>(message->ranges.size());
  codec->field(&count);
  message->ranges.resize(count);
  for (float& range : message->ranges) codec->field(&range);
}

}  // namespace

void writeSeeds() {
  for (bool backwards : {false, true}) {
    sensor_msgs::LaserScan message;
    message.angle_increment = backwards ? -0.25f : 0.25f;
    message.angle_min = backwards ? 1.0f : -1.0f;
    message.angle_max = -message.angle_min;
    message.range_min = 0.1f;
    message.range_max = 10.0f;
    message.ranges = {1.0f, 2.0f, INFINITY, -INFINITY, NAN, 0.05f, 12.0f, 10.0f, 0.1f};
    std::uint8_t no_return = backwards ? 1 : 0;
    writeSeed(backwards ? "seed_backwards" : "seed_forwards",
              encodeFields(describe<FuzzWriter>, &message, &no_return));
  }
}

}  // namespace fuzz
}  // namespace occupancy_fusion

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace occupancy_fusion;
  sensor_msgs::LaserScan message;
  std::uint8_t above_max_is_no_return = 0;
  fuzz::decodeFields(fuzz::describe<fuzz::FuzzReader>, data, size, &message,
                     &above_max_is_no_return);
  try {
    const LaserScan scan = checkedLaserScan(message);
    scan.validate();
    LaserRangeConfig config;
    config.above_range_max_is_no_return = above_max_is_no_return % 2 == 1;
    double previous_angle = -INFINITY;
    for (int beam = 0; beam < scan.beamCount(); ++beam) {
      const double angle = scan.angle(beam);
      if (!std::isfinite(angle) || !(angle >= previous_angle)) std::abort();
      previous_angle = angle;
      const BeamReading reading =
          classifyBeam(scan.ranges[beam], scan.range_min, scan.range_max, config);
      if (reading.kind == BeamKind::kHit &&
          !(reading.range >= scan.range_min && reading.range <= scan.range_max)) {
        std::abort();
      }
    }
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
