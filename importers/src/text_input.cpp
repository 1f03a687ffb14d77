#include "text_input.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>

namespace crackvis::importers {

Result<TextInput> TextInput::open(const std::string& path) {
  TextInput input;
  input.m_path = path;
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) {
    return notFound(fmt::format("{}: no such file", path));
  }
  input.m_in.open(path, std::ios::binary);
  if (!input.m_in) {
    return failedPrecondition(fmt::format("{}: cannot open", path));
  }
  return input;
}

bool TextInput::next(std::string& line) {
  if (!std::getline(m_in, line)) {
    return false;
  }
  ++m_line;
  if (!line.empty() && line.back() == '\r') {
    line.pop_back();
  }
  return true;
}

Result<std::string> TextInput::expect(const std::string& what) {
  std::string line;
  if (!next(line)) {
    return Status(StatusCode::kFailedPrecondition,
                  fmt::format("{}:{}: truncated: expected {}", m_path, m_line + 1, what));
  }
  return line;
}

Status TextInput::error(const std::string& message) const {
  return failedPrecondition(fmt::format("{}:{}: {}", m_path, m_line, message));
}

void TextInput::seek(std::streamoff offset, int line) {
  m_in.clear();
  m_in.seekg(offset);
  m_line = line;
}

std::streamoff TextInput::offset() {
  return m_in.tellg();
}

std::uint64_t TextInput::bytesLeft() {
  std::error_code error;
  const std::uintmax_t size = std::filesystem::file_size(m_path, error);
  const std::streamoff at = m_in.tellg();
  return error || at < 0 || static_cast<std::uintmax_t>(at) >= size
             ? 0
             : static_cast<std::uint64_t>(size - static_cast<std::uintmax_t>(at));
}

std::vector<std::string_view> splitTokens(std::string_view line) {
  std::vector<std::string_view> tokens;
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) {
      ++i;
    }
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t') {
      ++i;
    }
    if (i > start) {
      tokens.push_back(line.substr(start, i - start));
    }
  }
  return tokens;
}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t i = 0;
  auto separator = [](char c) { return c == ',' || c == ' ' || c == '\t' || c == ';'; };
  while (i < line.size()) {
    while (i < line.size() && separator(line[i])) {
      ++i;
    }
    const std::size_t start = i;
    while (i < line.size() && !separator(line[i])) {
      ++i;
    }
    if (i > start) {
      fields.push_back(line.substr(start, i - start));
    }
  }
  return fields;
}

bool parseNumber(std::string_view text, double& value) {
  if (!text.empty() && text.front() == '+') {
    text.remove_prefix(1);
  }
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size() && !text.empty();
}

bool parseId(std::string_view text, std::int64_t& value) {
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (error == std::errc() && end == text.data() + text.size() && !text.empty()) {
    return true;
  }
  double real = 0.0;
  if (!parseNumber(text, real) || !std::isfinite(real) || std::abs(real) > 9.0e15 ||
      real != std::floor(real)) {
    return false;
  }
  value = static_cast<std::int64_t>(real);
  return true;
}

std::string safeName(std::string_view text) {
  std::string name;
  for (char c : text) {
    const bool plain =
        std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_' || c == '.' || c == '-';
    name += plain ? c : '_';
  }
  while (!name.empty() && name.back() == '_') {
    name.pop_back();
  }
  return name.substr(0, 64);
}

std::vector<std::string> listFolder(const std::string& folder) {
  std::vector<std::string> files;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(folder, error)) {
    if (entry.is_regular_file(error)) {
      files.push_back(entry.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

bool isFolder(const std::string& path) {
  std::error_code error;
  return std::filesystem::is_directory(path, error);
}

std::string baseName(const std::string& path) {
  return std::filesystem::path(path).filename().string();
}

}  // namespace crackvis::importers
