#include "occupancy_fusion/map/block_change_log.h"

#include <algorithm>

#include "occupancy_fusion/map/spatial_key.h"

namespace occupancy_fusion {

void BlockChangeLog::finishWrite() {
  if (entries_.size() >= compact_at_) {
    compact();
    // Doubling keeps compaction amortised O(1) per entry even when most keys are distinct.
    compact_at_ = std::max(kMinCompactionSize, 2 * entries_.size());
  }
  while (entries_.size() > kMaxEntries) {
    start_ = entries_.front().version + 1;
    entries_.pop_front();
  }
}

void BlockChangeLog::compact() {
  SpatialKeySet seen;
  seen.reserve(entries_.size());
  std::deque<Entry> newest_first;
  for (auto it = entries_.rbegin(); it != entries_.rend(); ++it) {
    if (seen.insert(it->key).second) newest_first.push_back(*it);
  }
  entries_.assign(newest_first.rbegin(), newest_first.rend());
}

void BlockChangeLog::clear(std::uint64_t next_version) {
  entries_.clear();
  start_ = next_version;
  compact_at_ = kMinCompactionSize;
}

bool BlockChangeLog::collectSince(std::uint64_t version, std::vector<std::uint64_t>* changed,
                                  std::vector<std::uint64_t>* removed) const {
  if (version < start_) return false;
  const auto first =
      std::lower_bound(entries_.begin(), entries_.end(), version,
                       [](const Entry& entry, std::uint64_t v) { return entry.version < v; });
  // Newest first, so that each key is reported once, as its newest entry says.
  SpatialKeySet seen;
  std::vector<Entry> newest;
  for (auto it = entries_.end(); it != first;) {
    --it;
    if (seen.insert(it->key).second) newest.push_back(*it);
  }
  for (auto it = newest.rbegin(); it != newest.rend(); ++it) {
    if (!it->removed) {
      changed->push_back(it->key);
    } else if (removed != nullptr) {
      removed->push_back(it->key);
    }
  }
  return true;
}

}  // namespace occupancy_fusion
