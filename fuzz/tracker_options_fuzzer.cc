// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// ParseTrackerOptions (track/tracker_options.h): the input is the YAML text. Options it
// returns pass TrackerOptions::Check.
#include "fuzz/fuzz_support.h"
#include "unseen/track/tracker_options.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  const std::string text(fuzz::AsText(data, size));
  const std::string what = "tracker.yaml";
  fuzz::ExpectReaderContract("ParseTrackerOptions", what, [&] {
    const TrackerOptions options = ParseTrackerOptions(text, what);
    try {
      options.Check();
    } catch (const Error& e) {
      fuzz::Fail(std::string("ParseTrackerOptions returned options that fail their check: ") +
                 e.what());
    }
  });
  return 0;
}
