// Which blocks (or tiles) of a sparse map were written or removed after a given map version, so
// that consumers (the published markers, the projected grid) stay current at a cost that follows
// the change, not the map's size.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <vector>

namespace occupancy_fusion {

// Not synchronised: the owning map guards it with its own lock.
//
// A consumer that last looked at version v needs the keys with an entry at or after v, and a
// key's newest entry is its latest one, so older entries of the same key carry nothing: the log
// is compacted to one entry per key whenever it has doubled since the last compaction. It thus
// holds about one entry per block ever written, however many frames wrote them. kMaxEntries caps
// it; the oldest entries are then dropped and consumers older than them rebuild from scratch.
class BlockChangeLog {
 public:
  struct Entry {
    std::uint64_t version;
    std::uint64_t key;
    bool removed;
  };
  static constexpr std::size_t kMaxEntries = std::size_t{1} << 20;

  // Entries must come in non-decreasing version order (the map's write counter).
  void recordChange(std::uint64_t version, std::uint64_t key) {
    entries_.push_back({version, key, false});
  }
  void recordRemoval(std::uint64_t version, std::uint64_t key) {
    entries_.push_back({version, key, true});
  }
  // Compacts or trims; call once per write call, after its entries.
  void finishWrite();
  // Forgets everything: consumers older than next_version must rebuild.
  void clear(std::uint64_t next_version);

  // Keys with an entry at or after `version`, each once, in the order of their newest entries and
  // classified by them (a key removed and written again is changed); false when the log no
  // longer reaches back that far (rebuild from scratch).
  bool collectSince(std::uint64_t version, std::vector<std::uint64_t>* changed,
                    std::vector<std::uint64_t>* removed) const;

  std::size_t size() const { return entries_.size(); }
  std::size_t memoryBytes() const { return entries_.size() * sizeof(Entry); }

 private:
  void compact();

  std::deque<Entry> entries_;  // in version order
  std::uint64_t start_ = 1;    // versions before this are no longer fully in the log
  std::size_t compact_at_ = kMinCompactionSize;
  // Small, so that a small map's log stays small beside its blocks (a few dozen blocks written
  // every frame would otherwise keep up to this many entries); compacting a log this short costs
  // next to nothing.
  static constexpr std::size_t kMinCompactionSize = 32;
};

}  // namespace occupancy_fusion
