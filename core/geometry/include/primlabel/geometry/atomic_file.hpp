#pragma once
// The one way primlabel replaces a file: write a temporary file beside it, fsync it, rename it
// over the target and fsync the directory. Readers (and a crash or power loss) see either the old
// file or the whole new one, never a partial file, and once the call returns the new file is
// durable. Used for PCD, PLY, model files, PNG pictures, JSON and CSV reports and the uploader's
// spool.

#include <cstdio>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string_view>

namespace primlabel {

// What failed and why, starting with the path ("<path>: fsync failed: Input/output error").
class AtomicWriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct AtomicWriteOptions {
  // Where the temporary file goes; empty: the target's own directory. Must be on the target's
  // filesystem (rename cannot cross filesystems). The uploader's spool keeps its temporaries in
  // a directory of their own so that it can remove leftovers of a crash wholesale.
  std::filesystem::path temp_dir;
};

// Replaces `path` with `bytes`. On failure the temporary file is removed and `path` is left as it
// was, except when only the final directory fsync failed (the new file is then in place but may
// not survive a power loss; the error says so). Throws AtomicWriteError.
void atomic_write_file(const std::filesystem::path& path, std::string_view bytes,
                       const AtomicWriteOptions& options = {});

// Replaces `path` with whatever `write` writes to the stream it is given (for writers that
// produce their output piecewise, such as libpng). An exception from `write` is rethrown after
// the temporary file is removed; a stream error (ferror) after `write` returns fails the write.
void atomic_write_file(const std::filesystem::path& path,
                       const std::function<void(std::FILE*)>& write,
                       const AtomicWriteOptions& options = {});

// The temporary files atomic_write_file leaves when a crash interrupts it
// (".<name>.tmp.<pid>.<n>"), so that a directory's owner can remove them at start.
bool is_atomic_write_temp_name(std::string_view file_name);

// fsync of a file or a directory by path. Throws AtomicWriteError naming it.
void fsync_path(const std::filesystem::path& path);

}  // namespace primlabel
