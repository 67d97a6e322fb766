// What a stretch of writes did to a block of log-odds cells, and how such changes add up again:
// the submaps' storage (mapping/submap_fusion.h). A cell's change is the log-odds it gained, with
// an unknown cell taken at the prior (0), so that adding every stretch's change in turn, clamped,
// gives the map again; NaN means the stretch left the cell as it was.
#pragma once

#include <cmath>

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

}  // namespace occupancy_fusion
