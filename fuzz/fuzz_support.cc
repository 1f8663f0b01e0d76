// unseen — Copyright the unseen authors. SPDX-License-Identifier: BSD-3-Clause
#include "fuzz/fuzz_support.h"

#include <cxxabi.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <opencv2/core.hpp>

namespace unseen::fuzz {

void Init() {
  static const bool done = [] {
    spdlog::set_level(spdlog::level::off);
    cv::setNumThreads(0);
    return true;
  }();
  (void)done;
}

void Fail(const std::string& message) {
  std::fprintf(stderr, "\n==unseen fuzz== %s\n", message.c_str());
  std::fflush(stderr);
  std::abort();
}

std::string TypeName(const std::type_info& type) {
  int status = 0;
  char* name = abi::__cxa_demangle(type.name(), nullptr, nullptr, &status);
  std::string out = status == 0 && name != nullptr ? name : type.name();
  std::free(name);
  return out;
}

void ReportRejection(const std::string& reader, const std::string& message) {
  static const bool verbose = std::getenv("UNSEEN_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "%s rejected the input: %s\n", reader.c_str(), message.c_str());
}

Scratch::Scratch(const std::string& name)
    : dir_(std::filesystem::temp_directory_path() /
           fmt::format("unseen_fuzz_{}_{}", name, ::getpid())) {
  Reset();
}

Scratch::~Scratch() {
  std::error_code ec;
  std::filesystem::remove_all(dir_, ec);
}

void Scratch::Reset() const {
  std::filesystem::remove_all(dir_);
  std::filesystem::create_directories(dir_);
}

std::string Scratch::Write(const std::string& relative, std::string_view bytes) const {
  const std::filesystem::path path = dir_ / relative;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) Fail(fmt::format("cannot write scratch file {}", path.string()));
  return path.string();
}

bool Scratch::WriteBundle(const std::vector<BundleFile>& files) const {
  for (const BundleFile& file : files) {
    const std::filesystem::path path = dir_ / file.name;
    std::error_code ec;
    std::filesystem::create_directories(path.parent_path(), ec);
    if (ec || std::filesystem::is_directory(path)) return false;
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(file.bytes.data(), static_cast<std::streamsize>(file.bytes.size()));
    if (!out) return false;
  }
  return true;
}

bool IsBundleName(std::string_view name) {
  if (name.empty() || name.size() > 64) return false;
  int parts = 0;
  size_t start = 0;
  while (start <= name.size()) {
    const size_t slash = std::min(name.find('/', start), name.size());
    const std::string_view part = name.substr(start, slash - start);
    if (part.empty() || part == "." || part == ".." || ++parts > 3) return false;
    for (char c : part) {
      const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                      c == '_' || c == '.' || c == '-';
      if (!ok) return false;
    }
    start = slash + 1;
  }
  return true;
}

std::optional<std::vector<BundleFile>> SplitBundle(std::string_view input,
                                                   const std::string& main_name) {
  constexpr std::string_view kOpen = "==> ", kClose = " <==\n";
  std::vector<BundleFile> files;
  std::string name = main_name;
  size_t begin = 0;
  while (true) {
    size_t header = input.find(kOpen, begin);
    while (header != std::string_view::npos && header > 0 && input[header - 1] != '\n') {
      header = input.find(kOpen, header + 1);
    }
    const size_t end = header == std::string_view::npos ? input.size() : header;
    files.push_back({name, input.substr(begin, end - begin)});
    if (header == std::string_view::npos) break;
    const size_t close = input.find(kClose, header + kOpen.size());
    const size_t eol = input.find('\n', header);
    if (close == std::string_view::npos || close + kClose.size() - 1 != eol) return std::nullopt;
    const std::string_view next =
        input.substr(header + kOpen.size(), close - header - kOpen.size());
    if (!IsBundleName(next)) return std::nullopt;
    name = std::string(next);
    begin = close + kClose.size();
  }
  return files;
}

}  // namespace unseen::fuzz
