#include "occupancy_fusion/map/map_checkpoints.h"

#include <cstring>
#include <ctime>
#include <limits>
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

// The layer's tiles beyond its bound, in the map's store beside the blocks.
class MapTileStore : public TileStore {
 public:
  explicit MapTileStore(VoxelMap* voxels) : voxels_(voxels) {}
  bool put(const std::vector<std::pair<std::uint64_t, const GridTile*>>& tiles) override {
    std::vector<BlockStore::LayerRecord> records;
    records.reserve(tiles.size());
    for (const auto& [key, tile] : tiles) records.push_back(tileRecord(unpackKey2(key), *tile));
    return voxels_->spillLayerRecords(records);
  }
  bool get(std::uint64_t key, GridTile* out) const override {
    std::vector<unsigned char> bytes;
    if (!voxels_->readLayerRecord(key, &bytes) || bytes.size() != kTileBytes) return false;
    *out = GridTile();
    float value;
    for (int linear = 0; linear < GridTile::kArea; ++linear) {
      std::memcpy(&value, bytes.data() + linear * sizeof(float), sizeof(float));
      out->set(linear, value);  // counts the known cells
    }
    return true;
  }

 private:
  VoxelMap* voxels_;
};

}  // namespace

std::runtime_error MapCheckpoints::damagedTile(std::uint64_t key, std::size_t size) const {
  return std::runtime_error("block store '" + voxels_->config().spill_folder +
                            "': laser layer tile " + std::to_string(key) + " is damaged (" +
                            std::to_string(size) + " bytes)");
}

const std::uint64_t MapCheckpoints::kCompanionKey =
    packKey(TileIndex(std::numeric_limits<std::int32_t>::min(), 0));

GridLayer2DConfig laserLayerConfig(const VoxelMapConfig& map) {
  GridLayer2DConfig layer;
  layer.resolution = map.resolution;
  layer.model = map.model;
  layer.max_memory_bytes = map.layer_max_memory_bytes;
  return layer;
}

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
  if (layer_->config().max_memory_bytes > 0 && voxels_->hasStore()) {
    layer_->setTileStore(std::make_unique<MapTileStore>(voxels_));
  }
  // Only the keys under the map's lock: a restore beyond the layer's bound spills through the
  // map's exclusive lock, and the keys are a small fraction of the tiles' bytes.
  std::vector<std::uint64_t> keys;
  voxels_->forEachResumedLayerRecord(
      [&](std::uint64_t key, const unsigned char* bytes, std::size_t size) {
        if (key == kCompanionKey) {
          resumed_companion_.assign(bytes, bytes + size);
          return;
        }
        if (size != kTileBytes) throw damagedTile(key, size);
        keys.push_back(key);
      });
  GridTile tile;
  std::vector<unsigned char> bytes;
  for (std::uint64_t key : keys) {
    if (!voxels_->readLayerRecord(key, &bytes)) {
      throw std::runtime_error("block store '" + voxels_->config().spill_folder +
                               "': laser layer tile " + std::to_string(key) + " cannot be read");
    }
    if (bytes.size() != kTileBytes) throw damagedTile(key, bytes.size());
    std::memcpy(tile.log_odds.data(), bytes.data(), kTileBytes);
    layer_->restoreTile(unpackKey2(key), tile);
    ++resumed_tiles_;
  }
  // The restored tiles are in the checkpoint already.
  layer_version_ = layer_->version();
}

CheckpointResult MapCheckpoints::checkpoint(const std::string& stamp,
                                            const std::vector<unsigned char>* companion) {
  BlockStore::LayerRecords records;
  if (companion != nullptr) records.records.push_back({kCompanionKey, *companion});
  CheckpointResult result;
  // Under the layer's lock from collecting its tiles to the transaction: no tile changes or
  // leaves memory for the store in between.
  const GridChanges changes = layer_->visitChangedTiles(
      layer_version_,
      [&](const TileIndex& index, const GridTile& tile) {
        records.records.push_back(tileRecord(index, tile));
      },
      [&](const GridChanges& collected) {
        records.replace_all = collected.full_rebuild;
        result = voxels_->checkpoint(stamp, &records);
      });
  if (result.written) layer_version_ = changes.version;
  return result;
}

}  // namespace occupancy_fusion
