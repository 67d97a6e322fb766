// libFuzzer's start-up hook, linked into every harness: writes the harness's generated seeds into
// $FUZZ_SEED_DIR (fuzz_input.h), so each run starts from valid messages as well as the checked-in
// corpus.
#include "fuzz_input.h"

// A harness whose seeds are all checked in (fuzz_carmen_log) defines no writeSeeds(); this weak
// definition then stands in and writes none.
__attribute__((weak)) void occupancy_fusion::fuzz::writeSeeds() {}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  occupancy_fusion::fuzz::writeSeeds();
  return 0;
}
