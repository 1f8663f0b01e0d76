// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// ParseInterestFilterBank (select/interest_filter_bank.h): the input is the YAML text. A
// bank it returns applies to a small frame without error.
#include "fuzz/fuzz_support.h"
#include "unseen/select/interest_filter_bank.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  const std::string text(fuzz::AsText(data, size));
  const std::string what = "filters.yaml";
  fuzz::ExpectReaderContract("ParseInterestFilterBank", what, [&] {
    InterestFilterBank bank = ParseInterestFilterBank(text, what);
    FilterFrame frame;
    frame.image = cv::Mat(8, 8, CV_32FC3, cv::Scalar(0.2, 0.5, 0.8));
    frame.depth = cv::Mat(8, 8, CV_32FC1, cv::Scalar(1.0f));
    frame.camera = PinholeCamera::Centered(8, 8, 10.0);
    try {
      const cv::Mat interest = bank.Apply(frame);
      double lo = 0.0, hi = 0.0;
      cv::minMaxLoc(interest, &lo, &hi);
      if (lo < 0.0 || hi > 1.0) fuzz::Fail("an interest map left [0, 1]");
    } catch (const Error& e) {
      fuzz::Fail(std::string("a parsed bank failed on a valid frame: ") + e.what());
    }
  });
  return 0;
}
