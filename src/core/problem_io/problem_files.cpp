#include "problem_files.h"

#include <cctype>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace lcp_contact_solver::core {

namespace problem_files {

[[noreturn]] void fail(const std::string& path, const std::string& fault) {
  throw ProblemFileError(path + ": " + fault);
}

std::string baseName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

std::string printable(std::string_view token) {
  constexpr std::size_t kMaxShown = 24;
  std::string shown;
  for (char ch : token.substr(0, kMaxShown)) shown += std::isprint(static_cast<unsigned char>(ch)) ? ch : '?';
  if (token.size() > kMaxShown) shown += "...";
  return shown;
}

void checkReadableFile(const std::string& path) {
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(status)) fail(path, "cannot open file (no such file)");
  if (std::filesystem::is_directory(status)) fail(path, "cannot read: is a directory");
  if (std::filesystem::is_regular_file(status)) {
    const auto size = std::filesystem::file_size(path, ec);
    if (!ec && size > kMaxFileBytes) fail(path, "file is too large (" + std::to_string(size) + " bytes)");
  }
}

std::string readWholeFile(const std::string& path) {
  checkReadableFile(path);
  std::ifstream file(path, std::ios::binary);
  if (!file) fail(path, std::string("cannot open file (") + std::strerror(errno) + ")");
  std::ostringstream content;
  content << file.rdbuf();
  if (file.bad()) fail(path, "read error");
  return content.str();
}

bool hasHdf5Signature(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  for (std::streamoff offset = 0; file; offset = offset == 0 ? 512 : 2 * offset) {
    char head[kHdf5SignatureSize] = {};
    if (!file.seekg(offset) || !file.read(head, kHdf5SignatureSize)) return false;
    if (std::memcmp(head, kHdf5Signature, kHdf5SignatureSize) == 0) return true;
  }
  return false;
}

void requireValid(const std::string& path, const Problem& problem) {
  if (const std::string fault = validateProblem(problem, kMaxRows); !fault.empty()) fail(path, fault);
}

}  // namespace problem_files

Problem readProblemFile(const std::string& path) {
  problem_files::checkReadableFile(path);
  return problem_files::hasHdf5Signature(path) ? readFclibHdf5(path) : readSiconosDat(path);
}

}  // namespace lcp_contact_solver::core
