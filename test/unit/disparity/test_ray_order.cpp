// The order in which a frame's bundled rays are walked (orderByImageTiles): tile by tile along a
// Z-order curve, each tile's rays in their order. That the order changes no update is
// DisparityImageFormEqualsPointFormOnEveryPath's (the image form walks tile by tile, the point
// form in the points' order).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "../../../src/integrators/stereo/ray_bundles.h"

namespace occupancy_fusion {
namespace {

// Rays to the points of the given slots, nearest = farthest.
std::vector<BundledRay> raysTo(const std::vector<std::uint32_t>& slots) {
  std::vector<BundledRay> rays;
  for (std::uint32_t slot : slots) rays.push_back({slot, slot});
  return rays;
}

// The position along the Z-order curve written out bit by bit: u's bit k at 2k, v's at 2k + 1.
std::uint64_t zOrderByBits(std::uint32_t u, std::uint32_t v) {
  std::uint64_t position = 0;
  for (int bit = 0; bit < 16; ++bit) {
    position |= static_cast<std::uint64_t>(u >> bit & 1u) << (2 * bit);
    position |= static_cast<std::uint64_t>(v >> bit & 1u) << (2 * bit + 1);
  }
  return position;
}

TEST(RayOrderTest, AFullImageIsWalkedTileByTileInZOrder) {
  // 16 x 16 px: four tiles of 8 x 8, walked (0, 0), (1, 0), (0, 1), (1, 1), each row by row.
  constexpr int kColumns = 16;
  std::vector<std::uint32_t> slots(kColumns * kColumns);
  for (std::uint32_t slot = 0; slot < slots.size(); ++slot) slots[slot] = slot;
  std::vector<BundledRay> rays = raysTo(slots);
  orderByImageTiles(kColumns, &rays);
  ASSERT_EQ(rays.size(), slots.size());
  const int tiles[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  std::size_t next = 0;
  for (const auto& tile : tiles) {
    for (int row = 0; row < kRayTilePx; ++row) {
      for (int column = 0; column < kRayTilePx; ++column, ++next) {
        const std::uint32_t slot =
            (tile[1] * kRayTilePx + row) * kColumns + tile[0] * kRayTilePx + column;
        EXPECT_EQ(rays[next].farthest, slot) << "position " << next;
      }
    }
  }
}

TEST(RayOrderTest, SparseRaysOfAnyImageKeepTheirOrderWithinATile) {
  // A 45 px wide image (its last tile column 5 px wide), rays at scattered pixels, the nearest
  // point of each a neighbour of the farthest: every ray once, tiles in Z order, and within a
  // tile the order they came in.
  constexpr std::uint32_t kColumns = 45, kRows = 37;
  std::vector<BundledRay> rays;
  for (std::uint32_t slot = 0; slot < kColumns * kRows; slot += 1 + slot % 7) {
    rays.push_back({slot, slot + 1});
  }
  const std::vector<BundledRay> given = rays;
  orderByImageTiles(static_cast<int>(kColumns), &rays);
  ASSERT_EQ(rays.size(), given.size());
  auto zOrderOf = [&](const BundledRay& ray) {
    return zOrderByBits(ray.farthest % kColumns / kRayTilePx, ray.farthest / kColumns / kRayTilePx);
  };
  auto inputPosition = [&](const BundledRay& ray) {
    return std::find_if(given.begin(), given.end(),
                        [&](const BundledRay& g) { return g.farthest == ray.farthest; }) -
           given.begin();
  };
  std::vector<std::uint32_t> seen;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    EXPECT_EQ(rays[i].nearest, rays[i].farthest + 1);
    seen.push_back(rays[i].farthest);
    if (i == 0) continue;
    const std::uint64_t before = zOrderOf(rays[i - 1]), here = zOrderOf(rays[i]);
    EXPECT_LE(before, here) << "position " << i;
    if (before == here) {
      EXPECT_LT(inputPosition(rays[i - 1]), inputPosition(rays[i]));
    }
  }
  std::sort(seen.begin(), seen.end());
  EXPECT_TRUE(std::adjacent_find(seen.begin(), seen.end()) == seen.end());
}

TEST(RayOrderTest, RaysOfNoImageKeepTheirOrder) {
  std::vector<BundledRay> rays = raysTo({9, 3, 27, 1});
  orderByImageTiles(0, &rays);
  ASSERT_EQ(rays.size(), 4u);
  EXPECT_EQ(rays[0].farthest, 9u);
  EXPECT_EQ(rays[1].farthest, 3u);
  EXPECT_EQ(rays[2].farthest, 27u);
  EXPECT_EQ(rays[3].farthest, 1u);
}

}  // namespace
}  // namespace occupancy_fusion
