// The data root: the one folder whose files may be read (crackvis-data's
// root; crackvis-render's --data-root for --snapshot), and the rules that
// keep every path inside it. Also crackvis-render's rules for the paths its
// callers name, which it checks the same way before it asks crackvis-data.
//
// A path from a client is relative to the root and '/'-separated. It is
// refused when empty (for a file), absolute, over 4096 bytes, holds a NUL, or
// when any part is "..";
// "." and empty parts are dropped. The path is then resolved with symlinks
// followed, and refused when the real file lies outside the root, so a
// symlink may point anywhere inside the root but never out of it. Access
// checks use the resolved path, so a link cannot lend one user's folder to
// another.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>

#include <crackvis/common/status.hpp>

namespace crackvis {

struct ResolvedPath {
  std::string requested;           // normalized path as the client named it ("runs/a.h5")
  std::string relative;            // the real file's path from the root, after symlinks
  std::filesystem::path absolute;  // canonical absolute path, the one to open
};

class DataRoot {
 public:
  // The root must be an existing directory; it is canonicalized once.
  static Result<DataRoot> open(const std::string& root);

  const std::filesystem::path& path() const { return m_root; }

  // A regular file under the root: INVALID_ARGUMENT for a malformed path or a
  // folder, PERMISSION_DENIED for one that resolves outside the root,
  // NOT_FOUND when it does not exist.
  Result<ResolvedPath> resolveFile(std::string_view path) const;
  // A folder under the root; the empty path is the root itself.
  Result<ResolvedPath> resolveFolder(std::string_view path) const;

  // Checks a client path's syntax and returns it normalized ("a//./b" ->
  // "a/b"); the empty path stays empty.
  static Result<std::string> normalize(std::string_view path);

  // The NOT_FOUND of a missing file or folder; also the answer for one the
  // caller may not list, so that the two cannot be told apart.
  static Status notFound(std::string_view normalized, bool folder);

  // Whether a canonical path is the root or lies below it.
  bool contains(const std::filesystem::path& canonical) const;

 private:
  explicit DataRoot(std::filesystem::path root) : m_root(std::move(root)) {}
  Result<ResolvedPath> resolve(std::string_view path, bool wantFolder) const;

  std::filesystem::path m_root;
};

}  // namespace crackvis
