// Line-oriented reading of the text files DEM codes write, with every
// problem reported as "FILE:LINE: what" so a user can open the file there.
#pragma once

#include <charconv>
#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>
#include <vector>

#include <crackvis/common/status.hpp>

namespace crackvis::importers {

class TextInput {
 public:
  static Result<TextInput> open(const std::string& path);

  // The next line (without its end), false at the end of the file.
  bool next(std::string& line);
  // The next line, or DATA_LOSS "FILE:LINE: truncated: expected WHAT".
  Result<std::string> expect(const std::string& what);
  int lineNumber() const { return m_line; }
  const std::string& path() const { return m_path; }
  // "FILE:LINE: message" as FAILED_PRECONDITION.
  Status error(const std::string& message) const;
  // Seeks to a byte offset recorded by offset() (line numbers restart at `line`).
  void seek(std::streamoff offset, int line);
  std::streamoff offset();
  // Bytes between the read position and the end of the file: the most rows
  // a count in a header can be believed for (each row is a value and a line
  // end at least).
  std::uint64_t bytesLeft();

 private:
  std::string m_path;
  std::ifstream m_in;
  int m_line = 0;
};

// Whitespace-separated tokens of a line.
std::vector<std::string_view> splitTokens(std::string_view line);
// Comma-or-whitespace-separated fields (CSV tables).
std::vector<std::string_view> splitFields(std::string_view line);

bool parseNumber(std::string_view text, double& value);
// An integer id; also accepts an integral floating-point text ("12.0",
// "1.5e+06") that is exact, since some codes print ids through %g.
bool parseId(std::string_view text, std::int64_t& value);

// A column or array name as crackvis-dem names allow (dem::validateName):
// other characters become '_', at most 64 kept.
std::string safeName(std::string_view text);

// Adds each input: a folder's files (not recursive) that `wanted` accepts,
// and every file named directly (so a wrong one gets its own error).
template <typename Wanted, typename Add>
Status addInputs(const std::vector<std::string>& inputs, Wanted wanted, Add add);

// Files in `folder` (not recursive), sorted by name.
std::vector<std::string> listFolder(const std::string& folder);
bool isFolder(const std::string& path);
std::string baseName(const std::string& path);

template <typename Wanted, typename Add>
Status addInputs(const std::vector<std::string>& inputs, Wanted wanted, Add add) {
  for (const std::string& input : inputs) {
    if (!isFolder(input)) {
      CRACKVIS_RETURN_IF_ERROR(add(input));
      continue;
    }
    for (const std::string& file : listFolder(input)) {
      if (wanted(file)) {
        CRACKVIS_RETURN_IF_ERROR(add(file));
      }
    }
  }
  return Status::ok();
}

}  // namespace crackvis::importers
