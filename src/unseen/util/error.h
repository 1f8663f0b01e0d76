// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
//
// Errors for broken contracts and bad input. Library code throws `unseen::Error`
// whose message names the file, the field and the offending value; expected
// run-time outcomes (object lost, no candidate) are statuses, never exceptions.
#pragma once

#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace unseen {

// Bad input or a broken precondition. The message is complete and user-facing.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Throws Error with a fmt-formatted message.
template <typename... Args>
[[noreturn]] void ThrowError(fmt::format_string<Args...> format, Args&&... args) {
  throw Error(fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace unseen

// Throws unseen::Error with the formatted message unless `condition` holds.
#define UNSEEN_CHECK(condition, ...)                  \
  do {                                                \
    if (!(condition)) ::unseen::ThrowError(__VA_ARGS__); \
  } while (false)
