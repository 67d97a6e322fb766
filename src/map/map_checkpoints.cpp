#include "occupancy_fusion/map/map_checkpoints.h"

#include <cstring>
#include <ctime>
#include <stdexcept>
#include <vector>

#include "occupancy_fusion/map/spatial_key.h"

namespace occupancy_fusion {
namespace {

// A tile's record: its cells' log-odds as they are in memory (NaN: unknown).
constexpr std::size_t kTileBytes = sizeof(float) * GridTile::kArea;

BlockStore::LayerRecord tileRecord(const TileIndex& index, const GridTile& tile) {
  BlockStore::LayerRecord record;
  record.key = packKey(index);
  record.bytes.resize(kTileBytes);
  std::memcpy(record.bytes.data(), tile.log_odds.data(), kTileBytes);
  return record;
}

}  // namespace

std::string checkpointStampNow() {
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);  // the MapServer's timer thread and others: not std::gmtime's buffer
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%dT%H:%M:%SZ", &utc);
  return stamp;
}

MapCheckpoints::MapCheckpoints(VoxelMap* voxels, GridLayer2D* layer)
    : voxels_(voxels), layer_(layer) {
  GridTile tile;
  voxels_->forEachResumedLayerRecord(
      [&](std::uint64_t key, const unsigned char* bytes, std::size_t size) {
        if (size != kTileBytes) {
          throw std::runtime_error("block store '" + voxels_->config().spill_folder +
                                   "': laser layer tile " + std::to_string(key) + " is damaged (" +
                                   std::to_string(size) + " bytes)");
        }
        std::memcpy(tile.log_odds.data(), bytes, kTileBytes);
        layer_->restoreTile(unpackKey2(key), tile);
        ++resumed_tiles_;
      });
  // The restored tiles are in the checkpoint already.
  layer_version_ = layer_->version();
}

CheckpointResult MapCheckpoints::checkpoint(const std::string& stamp) {
  const GridChanges changes = layer_->changesSince(layer_version_);
  BlockStore::LayerRecords records;
  records.replace_all = changes.full_rebuild;
  GridTile tile;
  if (changes.full_rebuild) {
    layer_->forEachTile([&](const TileIndex& index, const GridTile& cells) {
      records.records.push_back(tileRecord(index, cells));
    });
  } else {
    for (const TileIndex& index : changes.changed) {
      if (layer_->copyTile(index, &tile)) records.records.push_back(tileRecord(index, tile));
    }
  }
  const CheckpointResult result = voxels_->checkpoint(stamp, &records);
  if (result.written) layer_version_ = changes.version;
  return result;
}

}  // namespace occupancy_fusion
