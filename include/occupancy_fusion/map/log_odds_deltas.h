// What a stretch of writes did to a block of log-odds cells, and how such changes add up again:
// the submaps' storage (mapping/submap_fusion.h). A cell's change is the log-odds it gained, with
// an unknown cell taken at the prior (0), so that adding every stretch's change in turn, clamped,
// gives the map again; NaN means the stretch left the cell as it was.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <istream>
#include <limits>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "occupancy_fusion/map/log_odds_cells.h"

namespace occupancy_fusion {

// The change from `before` to `after` of one cell: NaN when it is unchanged or unknown after
// (a block dropped by the memory bound is no evidence).
inline float logOddsChange(float before, float after) {
  if (std::isnan(after)) return std::nanf("");
  if (std::isnan(before)) return after;
  return after == before ? std::nanf("") : after - before;
}

// A cell after a change is added (the prior 0 for an unknown cell), clamped like every update.
inline float addLogOddsChange(float value, float change, float min_log_odds, float max_log_odds) {
  if (std::isnan(change)) return value;
  const float sum = (std::isnan(value) ? 0.0f : value) + change;
  return sum < min_log_odds ? min_log_odds : (sum > max_log_odds ? max_log_odds : sum);
}

// Cell by cell: the changes from `before` to `after` into `changes` (its known_count counts the
// cells with a change). Returns that count.
template <int kCount>
int logOddsChanges(const LogOddsCells<kCount>& before, const LogOddsCells<kCount>& after,
                   LogOddsCells<kCount>* changes) {
  int changed = 0;
  for (int i = 0; i < kCount; ++i) {
    const float change = logOddsChange(before.log_odds[i], after.log_odds[i]);
    changes->log_odds[i] = change;
    changed += std::isnan(change) ? 0 : 1;
  }
  changes->known_count = changed;
  return changed;
}

// Cell by cell: `changes` added to `cells`.
template <int kCount>
void addLogOddsChanges(const LogOddsCells<kCount>& changes, float min_log_odds, float max_log_odds,
                       LogOddsCells<kCount>* cells) {
  for (int i = 0; i < kCount; ++i) {
    cells->set(
        i, addLogOddsChange(cells->log_odds[i], changes.log_odds[i], min_log_odds, max_log_odds));
  }
}

namespace detail {
// LZ4 of a packed block's bytes (log_odds_deltas.cpp: the library stays private to the map).
std::unique_ptr<char[]> compressChanges(const char* raw, int raw_size, std::uint32_t* packed_size);
// Throws std::runtime_error when `packed` does not expand to exactly raw_size bytes.
void expandChanges(const char* packed, std::uint32_t packed_size, char* raw, int raw_size);
}  // namespace detail

// A block's (tile's) changes as the submaps keep them: a bit per cell that changed and, for those
// only, the change in steps of kStep log-odds (16 bits; |change| stays below the clamping range,
// far inside the +-32 they hold), the whole LZ4-compressed (the changes of a submap's frames
// repeat: free-space updates of one size, cells clamped alike; measured on the building loop, 2.3
// times smaller). Each change is rounded to a step away from the occupancy threshold on the side
// where the cell ended: added to the same `before` again it gives a cell classified as `after`
// was, also where `after` lies within a step of the threshold (a laser cell whose evidence
// cancels out to +1e-5 stays occupied, as in the map the sensors wrote). Rounding moves a change
// by less than kStep.
template <int kCount>
class PackedLogOddsChanges {
 public:
  static constexpr float kStep = 1.0f / 1024.0f;

  PackedLogOddsChanges() = default;
  PackedLogOddsChanges(const LogOddsCells<kCount>& before, const LogOddsCells<kCount>& after,
                       float threshold) {
    Raw raw;
    for (int i = 0; i < kCount; ++i) {
      const float change = logOddsChange(before.log_odds[i], after.log_odds[i]);
      if (std::isnan(change)) continue;
      raw.mask[i / 64] |= std::uint64_t{1} << (i % 64);
      const float steps =
          after.log_odds[i] > threshold ? std::ceil(change / kStep) : std::floor(change / kStep);
      const float limit = std::numeric_limits<std::int16_t>::max();
      raw.values[count_++] = static_cast<std::int16_t>(steps < -limit  ? -limit
                                                       : steps > limit ? limit
                                                                       : steps);
    }
    pack(raw);
  }

  // The changes, NaN where there is none.
  void expandInto(LogOddsCells<kCount>* out) const {
    out->log_odds.fill(std::numeric_limits<float>::quiet_NaN());
    Raw raw;
    unpack(&raw);
    std::uint32_t next = 0;
    for (int word = 0; word < kWords; ++word) {
      for (std::uint64_t bits = raw.mask[word]; bits != 0; bits &= bits - 1) {
        out->log_odds[word * 64 + __builtin_ctzll(bits)] = raw.values[next++] * kStep;
      }
    }
    out->known_count = static_cast<int>(count_);
  }
  std::size_t changed() const { return count_; }
  // As bytes (host order: files of this machine's kind): the mask, the count, the values.
  void writeTo(std::ostream& out) const {
    Raw raw;
    unpack(&raw);
    out.write(reinterpret_cast<const char*>(raw.mask.data()), sizeof(raw.mask));
    out.write(reinterpret_cast<const char*>(&count_), sizeof(count_));
    out.write(reinterpret_cast<const char*>(raw.values.data()),
              static_cast<std::streamsize>(count_ * sizeof(std::int16_t)));
  }
  // What writeTo wrote; false (the stream failed, or the count does not match the mask) otherwise.
  bool readFrom(std::istream& in) {
    Raw raw;
    std::uint32_t count = 0;
    in.read(reinterpret_cast<char*>(raw.mask.data()), sizeof(raw.mask));
    in.read(reinterpret_cast<char*>(&count), sizeof(count));
    std::size_t bits = 0;
    for (std::uint64_t word : raw.mask)
      bits += static_cast<std::size_t>(__builtin_popcountll(word));
    if (!in || bits != count) return false;
    in.read(reinterpret_cast<char*>(raw.values.data()),
            static_cast<std::streamsize>(count * sizeof(std::int16_t)));
    if (!in) return false;
    count_ = count;
    pack(raw);
    return true;
  }
  std::size_t bytes() const { return sizeof(*this) + packed_size_; }
  // As kept in memory (the count, then the compressed bytes), appended to *out, and back: what a
  // spill of the submaps writes and reads. false: not such bytes.
  void appendPackedTo(std::string* out) const {
    out->append(reinterpret_cast<const char*>(&count_), sizeof(count_));
    out->append(packed_.get(), packed_size_);
  }
  bool readPacked(const std::string& bytes) {
    if (bytes.size() < sizeof(count_)) return false;
    std::memcpy(&count_, bytes.data(), sizeof(count_));
    if (count_ > static_cast<std::uint32_t>(kCount)) return false;
    packed_size_ = static_cast<std::uint32_t>(bytes.size() - sizeof(count_));
    packed_ = packed_size_ > 0 ? std::make_unique<char[]>(packed_size_) : nullptr;
    if (packed_) std::memcpy(packed_.get(), bytes.data() + sizeof(count_), packed_size_);
    return count_ == 0 || packed_ != nullptr;
  }

 private:
  static constexpr int kWords = (kCount + 63) / 64;
  struct Raw {
    std::array<std::uint64_t, kWords> mask{};
    std::array<std::int16_t, kCount> values;
  };
  static constexpr int kMaskBytes = kWords * 8;
  static_assert(offsetof(Raw, values) == kMaskBytes, "Raw's values follow its mask");
  int rawSize() const { return kMaskBytes + static_cast<int>(count_ * sizeof(std::int16_t)); }

  // The mask and the first count_ values, compressed straight from Raw, where they lie
  // contiguously (checked below).
  void pack(const Raw& raw) {
    packed_ =
        detail::compressChanges(reinterpret_cast<const char*>(&raw), rawSize(), &packed_size_);
  }
  void unpack(Raw* raw) const {
    if (!packed_) return;  // empty: no cell changed
    detail::expandChanges(packed_.get(), packed_size_, reinterpret_cast<char*>(raw), rawSize());
  }

  std::uint32_t count_ = 0;
  std::uint32_t packed_size_ = 0;
  std::unique_ptr<char[]> packed_;
};

}  // namespace occupancy_fusion
