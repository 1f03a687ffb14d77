#include <array>
#include <fstream>

#include <crackvis/dataservice_h5/data_root.hpp>

namespace crackvis::dataservice {
namespace fs = std::filesystem;

bool hasHdf5Signature(const fs::path& file) {
  static constexpr std::array<char, 8> kSignature = {'\x89', 'H',  'D',    'F',
                                                     '\r',   '\n', '\x1a', '\n'};
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    return false;
  }
  std::error_code error;
  const std::uintmax_t size = fs::file_size(file, error);
  if (error) {
    return false;
  }
  for (std::uintmax_t offset = 0; offset + kSignature.size() <= size;
       offset = offset == 0 ? 512 : offset * 2) {
    std::array<char, 8> bytes{};
    in.seekg(static_cast<std::streamoff>(offset));
    if (!in.read(bytes.data(), bytes.size())) {
      return false;
    }
    if (bytes == kSignature) {
      return true;
    }
  }
  return false;
}

}  // namespace crackvis::dataservice
