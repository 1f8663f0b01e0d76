// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// What the fuzz targets share: the readers' contract (bad input throws unseen::Error whose
// message names the source; any other exception escaping is a bug), checks on what a
// reader accepted, a scratch folder for readers that take a path, and bundles (one input
// that holds several files).
#pragma once

#include <fmt/format.h>

#include <cstdint>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <typeinfo>
#include <vector>

#include "unseen/util/error.h"

namespace unseen::fuzz {

// Once per process: no log output (warnings about odd but valid input would flood the
// fuzzer's output), OpenCV on the calling thread only. Cheap to call on every input.
void Init();

// Reports a broken contract and aborts, so that libFuzzer keeps the input as a crash.
[[noreturn]] void Fail(const std::string& message);

// Fails with the formatted message unless `condition` holds.
#define UNSEEN_FUZZ_EXPECT(condition, ...)                                                     \
  do {                                                                                         \
    if (!(condition)) {                                                                        \
      ::unseen::fuzz::Fail(                                                                    \
          fmt::format("{}: expected {}: {}", __FILE__, #condition, fmt::format(__VA_ARGS__))); \
    }                                                                                          \
  } while (false)

// The demangled name of `type`.
std::string TypeName(const std::type_info& type);

// Prints the message of a rejected input when UNSEEN_FUZZ_VERBOSE is set in the environment.
void ReportRejection(const std::string& reader, const std::string& message);

// Runs `read()`, a reader given input named `source` (a path or a label). Rejecting the
// input with an unseen::Error whose message names `source` is the contract; an Error that
// does not name it, or any other exception, fails.
template <typename Fn>
void ExpectReaderContract(const std::string& reader, const std::string& source, Fn&& read) {
  try {
    read();
  } catch (const Error& e) {
    const std::string message = e.what();
    ReportRejection(reader, message);
    if (message.find(source) == std::string::npos) {
      Fail(fmt::format("{}: the error message does not name '{}': {}", reader, source, message));
    }
  } catch (const std::exception& e) {
    Fail(fmt::format("{}: {} escaped instead of unseen::Error: {}", reader, TypeName(typeid(e)),
                     e.what()));
  } catch (...) {
    Fail(fmt::format("{}: an exception of unknown type escaped", reader));
  }
}

// One file of a bundle: a relative path and its bytes.
struct BundleFile {
  std::string name;
  std::string_view bytes;
};

// A folder of this process for the files a reader is given: <temp>/unseen_fuzz_<name>_<pid>,
// emptied by Reset() and removed when the process exits normally.
class Scratch {
 public:
  explicit Scratch(const std::string& name);
  ~Scratch();
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;

  const std::filesystem::path& dir() const { return dir_; }
  void Reset() const;
  // Writes `bytes` to `relative` inside the folder (creating its folders); returns the path.
  std::string Write(const std::string& relative, std::string_view bytes) const;
  // Writes the files of a bundle; false when one cannot be written (its name is taken by a
  // folder, or a folder it needs by a file).
  bool WriteBundle(const std::vector<BundleFile>& files) const;

 private:
  std::filesystem::path dir_;
};

inline std::string_view AsText(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A relative path of at most 3 parts made of [A-Za-z0-9_.-], none of them "." or "..".
bool IsBundleName(std::string_view name);

// Splits an input into files. The bytes before the first header line "==> NAME <==" are
// the file `main_name`; each header starts the file NAME (the layout `head a b` prints).
// Returns nullopt when a header names no valid relative path (see IsBundleName).
std::optional<std::vector<BundleFile>> SplitBundle(std::string_view input,
                                                   const std::string& main_name);

}  // namespace unseen::fuzz
