#include "occupancy_fusion/map/block_store.h"

#include <fcntl.h>
#include <lmdb.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "occupancy_fusion/map/stored_block.h"

namespace occupancy_fusion {
namespace {

constexpr char kBlocksTable[] = "blocks";  // spilled since the last checkpoint
constexpr char kCheckpointTable[] = "checkpoint";
constexpr char kLayerTable[] = "layer_checkpoint";      // a companion layer's records
constexpr char kLayerSpilledTable[] = "layer_spilled";  // its records spilled since
constexpr char kMetaTable[] = "meta";
constexpr char kCheckpointCountKey[] = "checkpoint_count";
constexpr char kCheckpointStampKey[] = "checkpoint_stamp";
constexpr char kFormatKey[] = "format_version";
constexpr char kBlockSideKey[] = "block_side";
constexpr char kResolutionKey[] = "resolution";
constexpr char kLockFile[] = "in_use.lock";

// Keys are stored big-endian, so LMDB's byte order is the keys' numeric order on every machine.
struct KeyBytes {
  explicit KeyBytes(std::uint64_t key) {
    for (int i = 0; i < 8; ++i) bytes[i] = static_cast<unsigned char>(key >> (56 - 8 * i));
  }
  static std::uint64_t decode(const MDB_val& value) {
    std::uint64_t key = 0;
    const auto* bytes = static_cast<const unsigned char*>(value.mv_data);
    for (std::size_t i = 0; i < value.mv_size; ++i) key = (key << 8) | bytes[i];
    return key;
  }
  MDB_val value() { return {sizeof(bytes), bytes}; }
  unsigned char bytes[8];
};

// The value views the text: `text` must outlive it (a C string literal, or a string kept alive).
MDB_val textValue(const std::string& text) { return {text.size(), const_cast<char*>(text.data())}; }
MDB_val textValue(const char* text) { return {std::strlen(text), const_cast<char*>(text)}; }

// The shortest decimal that reads back as exactly `resolution` (for the metadata and messages).
std::string formatResolution(double resolution) {
  char text[32];
  for (int digits = 1; digits <= 17; ++digits) {
    std::snprintf(text, sizeof(text), "%.*g", digits, resolution);
    if (std::strtod(text, nullptr) == resolution) break;
  }
  return text;
}

// A transaction that is aborted unless committed.
class Transaction {
 public:
  Transaction(MDB_env* env, unsigned int flags) {
    code_ = mdb_txn_begin(env, nullptr, flags, &txn_);
    if (code_ != MDB_SUCCESS) txn_ = nullptr;
  }
  ~Transaction() { abort(); }
  Transaction(const Transaction&) = delete;
  Transaction& operator=(const Transaction&) = delete;

  int beginCode() const { return code_; }
  MDB_txn* get() const { return txn_; }
  int commit() { return mdb_txn_commit(std::exchange(txn_, nullptr)); }
  void abort() {
    if (txn_ != nullptr) mdb_txn_abort(std::exchange(txn_, nullptr));
  }

 private:
  int code_ = MDB_SUCCESS;
  MDB_txn* txn_ = nullptr;
};

class Cursor {
 public:
  Cursor(MDB_txn* txn, MDB_dbi dbi) { code_ = mdb_cursor_open(txn, dbi, &cursor_); }
  ~Cursor() {
    if (code_ == MDB_SUCCESS) mdb_cursor_close(cursor_);
  }
  Cursor(const Cursor&) = delete;
  Cursor& operator=(const Cursor&) = delete;
  int openCode() const { return code_; }
  MDB_cursor* get() const { return cursor_; }

 private:
  int code_ = MDB_SUCCESS;
  MDB_cursor* cursor_ = nullptr;
};

std::optional<std::string> readText(MDB_txn* txn, MDB_dbi dbi, const char* key) {
  MDB_val name = textValue(key);
  MDB_val value;
  if (mdb_get(txn, dbi, &name, &value) != MDB_SUCCESS) return std::nullopt;
  return std::string(static_cast<const char*>(value.mv_data), value.mv_size);
}

// Every entry of table `from` put into `to` (replacing entries of the same key).
int copyTable(MDB_txn* txn, MDB_dbi from, MDB_dbi to) {
  Cursor cursor(txn, from);
  if (cursor.openCode() != MDB_SUCCESS) return cursor.openCode();
  MDB_val name, value;
  int code = mdb_cursor_get(cursor.get(), &name, &value, MDB_FIRST);
  for (; code == MDB_SUCCESS; code = mdb_cursor_get(cursor.get(), &name, &value, MDB_NEXT)) {
    code = mdb_put(txn, to, &name, &value, 0);
    if (code != MDB_SUCCESS) return code;
  }
  return code == MDB_NOTFOUND ? MDB_SUCCESS : code;
}

}  // namespace

BlockStore::BlockStore(const BlockStoreConfig& config) : config_(config) {
  std::error_code error;
  std::filesystem::create_directories(config_.folder, error);
  if (error) {
    throw std::runtime_error("block store '" + config_.folder +
                             "': cannot create the folder: " + error.message());
  }
  lockFolder();
  try {
    open();
    checkOrWriteMetadata();
  } catch (...) {
    close();
    throw;
  }
}

BlockStore::~BlockStore() { close(); }

void BlockStore::close() {
  mdb_env_close(env_);  // accepts nullptr
  env_ = nullptr;
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
  lock_fd_ = -1;
}

void BlockStore::lockFolder() {
  // LMDB must not open one environment twice in a process, and two maps would empty and
  // overwrite each other's blocks: one store, one user. flock conflicts between two opens in one
  // process as between processes, and ends with the process.
  const std::string path = config_.folder + "/" + kLockFile;
  lock_fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0664);
  if (lock_fd_ < 0) {
    throw std::runtime_error("block store '" + config_.folder + "': cannot create " + kLockFile +
                             ": " + std::strerror(errno));
  }
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw std::runtime_error("block store '" + config_.folder + "': " +
                             (error == EWOULDBLOCK ? std::string("in use by another map")
                                                   : std::string(std::strerror(error))));
  }
}

void BlockStore::fail(const std::string& what, int code) const {
  throw std::runtime_error("block store '" + config_.folder + "': " + what + " (" +
                           mdb_strerror(code) + ")");
}

void BlockStore::open() {
  int code = mdb_env_create(&env_);
  if (code != MDB_SUCCESS) fail("cannot create an LMDB environment", code);
  std::size_t initial = config_.initial_bytes;
  if (config_.max_bytes != 0 && initial > config_.max_bytes) initial = config_.max_bytes;
  code = mdb_env_set_maxdbs(env_, 5);
  if (code == MDB_SUCCESS) code = mdb_env_set_mapsize(env_, initial);
  // MDB_NOTLS: a read transaction is not tied to its thread, so reads can nest (a forEach
  // callback reading a voxel).
  if (code == MDB_SUCCESS)
    code = mdb_env_open(env_, config_.folder.c_str(), MDB_NOTLS | MDB_NOSYNC, 0664);
  if (code != MDB_SUCCESS) {
    mdb_env_close(env_);
    env_ = nullptr;
    fail(code == MDB_INVALID || code == MDB_VERSION_MISMATCH ? "not an LMDB store, or a damaged one"
                                                             : "cannot open the store",
         code);
  }
}

void BlockStore::checkOrWriteMetadata() {
  Transaction txn(env_, 0);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot write to the store", txn.beginCode());
  int code = mdb_dbi_open(txn.get(), kMetaTable, MDB_CREATE, &meta_dbi_);
  if (code == MDB_SUCCESS) code = mdb_dbi_open(txn.get(), kBlocksTable, MDB_CREATE, &blocks_dbi_);
  if (code == MDB_SUCCESS) {
    code = mdb_dbi_open(txn.get(), kCheckpointTable, MDB_CREATE, &checkpoint_dbi_);
  }
  if (code == MDB_SUCCESS) code = mdb_dbi_open(txn.get(), kLayerTable, MDB_CREATE, &layer_dbi_);
  if (code == MDB_SUCCESS) {
    code = mdb_dbi_open(txn.get(), kLayerSpilledTable, MDB_CREATE, &layer_spilled_dbi_);
  }
  if (code != MDB_SUCCESS)
    fail("not a block store, or a damaged one: its tables do not open", code);
  const std::optional<std::string> format = readText(txn.get(), meta_dbi_, kFormatKey);
  const std::optional<std::string> side = readText(txn.get(), meta_dbi_, kBlockSideKey);
  const std::optional<std::string> resolution = readText(txn.get(), meta_dbi_, kResolutionKey);
  const std::string expected_resolution = formatResolution(config_.resolution);
  if (!format && !side && !resolution) {
    MDB_stat spilled, checkpointed;
    mdb_stat(txn.get(), blocks_dbi_, &spilled);
    mdb_stat(txn.get(), checkpoint_dbi_, &checkpointed);
    if (spilled.ms_entries != 0 || checkpointed.ms_entries != 0) {
      throw std::runtime_error("block store '" + config_.folder +
                               "': holds blocks but no metadata (damaged)");
    }
    const std::pair<const char*, std::string> entries[] = {
        {kFormatKey, std::to_string(kFormatVersion)},
        {kBlockSideKey, std::to_string(VoxelBlock::kSide)},
        {kResolutionKey, expected_resolution}};
    for (const auto& [key, text] : entries) {
      MDB_val name = textValue(key);
      MDB_val value = textValue(text);
      code = mdb_put(txn.get(), meta_dbi_, &name, &value, 0);
      if (code != MDB_SUCCESS) fail("cannot write the metadata", code);
    }
  } else if (!format || !side || !resolution) {
    throw std::runtime_error("block store '" + config_.folder +
                             "': its metadata is incomplete (damaged)");
  } else if (*format != std::to_string(kFormatVersion)) {
    throw std::runtime_error("block store '" + config_.folder + "': format version " + *format +
                             ", this program reads version " + std::to_string(kFormatVersion));
  } else if (*side != std::to_string(VoxelBlock::kSide)) {
    throw std::runtime_error("block store '" + config_.folder + "': blocks of " + *side +
                             " voxels a side, this program's have " +
                             std::to_string(VoxelBlock::kSide));
  } else if (*resolution != expected_resolution) {
    throw std::runtime_error("block store '" + config_.folder + "': written with resolution " +
                             *resolution + " m, the map's is " + expected_resolution +
                             " m (use the same resolution or another folder)");
  }
  code = txn.commit();
  if (code != MDB_SUCCESS) fail("cannot write the metadata", code);
}

std::size_t BlockStore::sizeLimit() const {
  MDB_envinfo info;
  mdb_env_info(env_, &info);
  return info.me_mapsize;
}

void BlockStore::grow(std::size_t current) {
  if (config_.max_bytes != 0 && current >= config_.max_bytes) {
    throw std::runtime_error("block store '" + config_.folder + "': full, it holds its limit of " +
                             std::to_string(config_.max_bytes) + " bytes");
  }
  std::size_t next = current * 2;
  if (config_.max_bytes != 0 && next > config_.max_bytes) next = config_.max_bytes;
  std::unique_lock<std::shared_mutex> lock(remap_mutex_);  // not while sync() flushes the map
  const int code = mdb_env_set_mapsize(env_, next);
  if (code != MDB_SUCCESS) fail("cannot grow to " + std::to_string(next) + " bytes", code);
}

void BlockStore::put(const std::vector<std::uint64_t>& keys, const BlockSource& block_at) {
  std::vector<unsigned char> encoded;
  for (;;) {
    const std::size_t limit = sizeLimit();
    Transaction txn(env_, 0);
    if (txn.beginCode() != MDB_SUCCESS) fail("cannot write", txn.beginCode());
    int code = MDB_SUCCESS;
    for (std::size_t i = 0; i < keys.size() && code == MDB_SUCCESS; ++i) {
      BrickEncoding::encode(block_at(i), &encoded);
      KeyBytes key(keys[i]);
      MDB_val name = key.value();
      MDB_val value{encoded.size(), encoded.data()};
      code = mdb_put(txn.get(), blocks_dbi_, &name, &value, 0);
    }
    if (code == MDB_SUCCESS) code = txn.commit();
    if (code == MDB_MAP_FULL) {
      txn.abort();  // a map can only grow with no transaction open
      grow(limit);
      continue;
    }
    if (code != MDB_SUCCESS) fail("cannot write " + std::to_string(keys.size()) + " blocks", code);
    return;
  }
}

void BlockStore::put(std::uint64_t key, const VoxelBlock& block) {
  put({key}, [&](std::size_t) -> const VoxelBlock& { return block; });
}

bool BlockStore::get(std::uint64_t key, VoxelBlock* out) const {
  // A read may run beside a writer that grows the map (VoxelMap reads ahead of its lock).
  std::shared_lock<std::shared_mutex> lock(remap_mutex_);
  Transaction txn(env_, MDB_RDONLY);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot read", txn.beginCode());
  KeyBytes key_bytes(key);
  MDB_val name = key_bytes.value();
  MDB_val value;
  int code = mdb_get(txn.get(), blocks_dbi_, &name, &value);
  if (code == MDB_NOTFOUND) code = mdb_get(txn.get(), checkpoint_dbi_, &name, &value);
  if (code == MDB_NOTFOUND) return false;
  if (code != MDB_SUCCESS) fail("cannot read block " + std::to_string(key), code);
  if (!BrickEncoding::decode(value.mv_data, value.mv_size, out)) {
    throw std::runtime_error("block store '" + config_.folder + "': block " + std::to_string(key) +
                             " is damaged (" + std::to_string(value.mv_size) +
                             " bytes, no block encoding)");
  }
  return true;
}

void BlockStore::walk(MDB_txn* txn, const EntryFn& fn) const {
  // The spill table and the checkpoint table, both in key order, merged; a key in both is the
  // spilled block (newer than its checkpoint).
  Cursor spilled(txn, blocks_dbi_), checkpointed(txn, checkpoint_dbi_);
  if (spilled.openCode() != MDB_SUCCESS) fail("cannot read", spilled.openCode());
  if (checkpointed.openCode() != MDB_SUCCESS) fail("cannot read", checkpointed.openCode());
  MDB_val spilled_key, spilled_value, checkpoint_key, checkpoint_value;
  int spilled_code = mdb_cursor_get(spilled.get(), &spilled_key, &spilled_value, MDB_FIRST);
  int checkpoint_code =
      mdb_cursor_get(checkpointed.get(), &checkpoint_key, &checkpoint_value, MDB_FIRST);
  auto keyOf = [&](const MDB_val& name) {
    const std::uint64_t key = KeyBytes::decode(name);
    if (name.mv_size != sizeof(key)) {
      throw std::runtime_error("block store '" + config_.folder + "': entry " +
                               std::to_string(key) + " is damaged");
    }
    return key;
  };
  while (spilled_code == MDB_SUCCESS || checkpoint_code == MDB_SUCCESS) {
    const bool has_spilled = spilled_code == MDB_SUCCESS;
    const bool has_checkpoint = checkpoint_code == MDB_SUCCESS;
    const std::uint64_t next_spilled = has_spilled ? keyOf(spilled_key) : 0;
    const std::uint64_t next_checkpoint = has_checkpoint ? keyOf(checkpoint_key) : 0;
    if (has_spilled && (!has_checkpoint || next_spilled <= next_checkpoint)) {
      fn(next_spilled, spilled_value);
      if (has_checkpoint && next_checkpoint == next_spilled) {
        checkpoint_code =
            mdb_cursor_get(checkpointed.get(), &checkpoint_key, &checkpoint_value, MDB_NEXT);
      }
      spilled_code = mdb_cursor_get(spilled.get(), &spilled_key, &spilled_value, MDB_NEXT);
    } else {
      fn(next_checkpoint, checkpoint_value);
      checkpoint_code =
          mdb_cursor_get(checkpointed.get(), &checkpoint_key, &checkpoint_value, MDB_NEXT);
    }
  }
  if (spilled_code != MDB_NOTFOUND) fail("cannot read", spilled_code);
  if (checkpoint_code != MDB_NOTFOUND) fail("cannot read", checkpoint_code);
}

void BlockStore::forEach(const std::function<void(std::uint64_t, const VoxelBlock&)>& fn) const {
  Transaction txn(env_, MDB_RDONLY);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot read", txn.beginCode());
  VoxelBlock block;
  walk(txn.get(), [&](std::uint64_t key, const MDB_val& value) {
    if (!BrickEncoding::decode(value.mv_data, value.mv_size, &block)) {
      throw std::runtime_error("block store '" + config_.folder + "': entry " +
                               std::to_string(key) + " is damaged");
    }
    fn(key, block);
  });
}

void BlockStore::clear() { drop(true); }

void BlockStore::clearSpilled() { drop(false); }

void BlockStore::drop(bool checkpoint_too) {
  Transaction txn(env_, 0);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot write", txn.beginCode());
  int code = mdb_drop(txn.get(), blocks_dbi_, 0);
  if (code == MDB_SUCCESS) code = mdb_drop(txn.get(), layer_spilled_dbi_, 0);
  if (code == MDB_SUCCESS && checkpoint_too) code = mdb_drop(txn.get(), checkpoint_dbi_, 0);
  if (code == MDB_SUCCESS && checkpoint_too) code = mdb_drop(txn.get(), layer_dbi_, 0);
  if (code == MDB_SUCCESS && checkpoint_too) {
    for (const char* key : {kCheckpointCountKey, kCheckpointStampKey}) {
      MDB_val name = textValue(key);
      code = mdb_del(txn.get(), meta_dbi_, &name, nullptr);
      if (code == MDB_NOTFOUND) code = MDB_SUCCESS;
      if (code != MDB_SUCCESS) break;
    }
  }
  if (code == MDB_SUCCESS) code = txn.commit();
  if (code != MDB_SUCCESS) fail("cannot remove the blocks", code);
}

int BlockStore::writeCheckpoint(MDB_txn* txn, const std::vector<std::uint64_t>& keys,
                                const BlockSource& block_at,
                                const std::vector<std::uint64_t>& removed,
                                const CheckpointInfo& info, const LayerRecords* layer) {
  // 1. The blocks spilled since the last checkpoint join it (spilled blocks are the map's newest).
  int code = copyTable(txn, blocks_dbi_, checkpoint_dbi_);
  if (code == MDB_SUCCESS) code = mdb_drop(txn, blocks_dbi_, 0);
  // 2. The blocks in memory written since, over them.
  std::vector<unsigned char> encoded;
  for (std::size_t i = 0; i < keys.size() && code == MDB_SUCCESS; ++i) {
    BrickEncoding::encode(block_at(i), &encoded);
    KeyBytes key(keys[i]);
    MDB_val name = key.value();
    MDB_val value{encoded.size(), encoded.data()};
    code = mdb_put(txn, checkpoint_dbi_, &name, &value, 0);
  }
  // 3. The blocks the map lost since.
  for (std::size_t i = 0; i < removed.size() && code == MDB_SUCCESS; ++i) {
    KeyBytes key(removed[i]);
    MDB_val name = key.value();
    code = mdb_del(txn, checkpoint_dbi_, &name, nullptr);
    if (code == MDB_NOTFOUND) code = MDB_SUCCESS;
  }
  // 4. The companion layer's records: those it spilled since join the checkpoint (unless all are
  //    written again), then the records written since over them.
  if (code == MDB_SUCCESS && layer != nullptr && layer->replace_all) {
    code = mdb_drop(txn, layer_dbi_, 0);
  } else if (code == MDB_SUCCESS) {
    code = copyTable(txn, layer_spilled_dbi_, layer_dbi_);
  }
  if (code == MDB_SUCCESS) code = mdb_drop(txn, layer_spilled_dbi_, 0);
  for (std::size_t i = 0; layer != nullptr && i < layer->records.size() && code == MDB_SUCCESS;
       ++i) {
    const LayerRecord& record = layer->records[i];
    KeyBytes key(record.key);
    MDB_val name = key.value();
    MDB_val value{record.bytes.size(), const_cast<unsigned char*>(record.bytes.data())};
    code = mdb_put(txn, layer_dbi_, &name, &value, 0);
  }
  const std::pair<const char*, std::string> entries[] = {
      {kCheckpointCountKey, std::to_string(info.count)}, {kCheckpointStampKey, info.stamp}};
  for (const auto& [key, text] : entries) {
    if (code != MDB_SUCCESS) break;
    MDB_val name = textValue(key);
    MDB_val value = textValue(text);
    code = mdb_put(txn, meta_dbi_, &name, &value, 0);
  }
  return code;
}

void BlockStore::checkpoint(const std::vector<std::uint64_t>& keys, const BlockSource& block_at,
                            const std::vector<std::uint64_t>& removed, const CheckpointInfo& info,
                            const LayerRecords* layer) {
  for (;;) {
    const std::size_t limit = sizeLimit();
    Transaction txn(env_, 0);
    if (txn.beginCode() != MDB_SUCCESS) fail("cannot write", txn.beginCode());
    int code = writeCheckpoint(txn.get(), keys, block_at, removed, info, layer);
    if (code == MDB_SUCCESS) code = txn.commit();
    if (code == MDB_MAP_FULL) {
      txn.abort();
      grow(limit);
      continue;
    }
    if (code != MDB_SUCCESS) fail("cannot write the checkpoint", code);
    return;
  }
}

void BlockStore::forEachLayerRecord(
    const std::function<void(std::uint64_t, const unsigned char*, std::size_t)>& fn) const {
  Transaction txn(env_, MDB_RDONLY);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot read", txn.beginCode());
  Cursor cursor(txn.get(), layer_dbi_);
  if (cursor.openCode() != MDB_SUCCESS) fail("cannot read", cursor.openCode());
  MDB_val name, value;
  int code = mdb_cursor_get(cursor.get(), &name, &value, MDB_FIRST);
  for (; code == MDB_SUCCESS; code = mdb_cursor_get(cursor.get(), &name, &value, MDB_NEXT)) {
    fn(KeyBytes::decode(name), static_cast<const unsigned char*>(value.mv_data), value.mv_size);
  }
  if (code != MDB_NOTFOUND) fail("cannot read the layer", code);
}

void BlockStore::putLayer(const std::vector<LayerRecord>& records) {
  for (;;) {
    const std::size_t limit = sizeLimit();
    Transaction txn(env_, 0);
    if (txn.beginCode() != MDB_SUCCESS) fail("cannot write", txn.beginCode());
    int code = MDB_SUCCESS;
    for (std::size_t i = 0; i < records.size() && code == MDB_SUCCESS; ++i) {
      KeyBytes key(records[i].key);
      MDB_val name = key.value();
      MDB_val value{records[i].bytes.size(), const_cast<unsigned char*>(records[i].bytes.data())};
      code = mdb_put(txn.get(), layer_spilled_dbi_, &name, &value, 0);
    }
    if (code == MDB_SUCCESS) code = txn.commit();
    if (code == MDB_MAP_FULL) {
      txn.abort();
      grow(limit);
      continue;
    }
    if (code != MDB_SUCCESS) {
      fail("cannot write " + std::to_string(records.size()) + " layer records", code);
    }
    return;
  }
}

bool BlockStore::getLayer(std::uint64_t key, std::vector<unsigned char>* bytes) const {
  Transaction txn(env_, MDB_RDONLY);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot read", txn.beginCode());
  KeyBytes key_bytes(key);
  MDB_val name = key_bytes.value();
  MDB_val value;
  int code = mdb_get(txn.get(), layer_spilled_dbi_, &name, &value);
  if (code == MDB_NOTFOUND) code = mdb_get(txn.get(), layer_dbi_, &name, &value);
  if (code == MDB_NOTFOUND) return false;
  if (code != MDB_SUCCESS) fail("cannot read layer record " + std::to_string(key), code);
  const auto* first = static_cast<const unsigned char*>(value.mv_data);
  bytes->assign(first, first + value.mv_size);
  return true;
}

std::optional<BlockStore::CheckpointInfo> BlockStore::lastCheckpoint() const {
  Transaction txn(env_, MDB_RDONLY);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot read", txn.beginCode());
  const std::optional<std::string> count = readText(txn.get(), meta_dbi_, kCheckpointCountKey);
  const std::optional<std::string> stamp = readText(txn.get(), meta_dbi_, kCheckpointStampKey);
  if (!count || !stamp) return std::nullopt;
  CheckpointInfo info;
  info.count = std::strtoull(count->c_str(), nullptr, 10);
  info.stamp = *stamp;
  return info;
}

void BlockStore::sync() {
  std::shared_lock<std::shared_mutex> lock(remap_mutex_);
  const int code = mdb_env_sync(env_, 1);
  if (code != MDB_SUCCESS) fail("cannot flush to disk", code);
}

std::size_t BlockStore::size() const {
  Transaction txn(env_, MDB_RDONLY);
  if (txn.beginCode() != MDB_SUCCESS) fail("cannot read", txn.beginCode());
  std::size_t count = 0;
  walk(txn.get(), [&](std::uint64_t, const MDB_val&) { ++count; });
  return count;
}

}  // namespace occupancy_fusion
