// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// ParseModellerOptions (model/modeller.h): the input is the YAML text. Options it returns
// pass ModellerOptions::Check.
#include "fuzz/fuzz_support.h"
#include "unseen/model/modeller.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace unseen;
  fuzz::Init();
  const std::string text(fuzz::AsText(data, size));
  const std::string what = "model.yaml";
  fuzz::ExpectReaderContract("ParseModellerOptions", what, [&] {
    const ModellerOptions options = ParseModellerOptions(text, what);
    try {
      options.Check();
    } catch (const Error& e) {
      fuzz::Fail(std::string("ParseModellerOptions returned options that fail their check: ") +
                 e.what());
    }
  });
  return 0;
}
