// Files published whole or not at all, and still there after a power cut:
// the one way Penumbra writes a file a user keeps (models, training-set
// pieces, lookup images, the rig JSON and the colour map's backups).
//
// The steps, as SQLite and LMDB take them: write a temporary file beside the
// target, fsync it, rename it over the target, fsync the folder. Without the
// first fsync, ext4 and others may commit the rename before the data and
// leave an empty file where a good one stood; without the second, the rename
// itself may be lost. A failed fsync is an IoError: before the rename the old
// target is left as it was, and the temporary never stays behind. Tests see
// the steps through common/fault_injection.hpp.
#pragma once

#include <functional>
#include <string>
#include <string_view>

namespace penumbra {

// Calls `write(temporary_path)`, then publishes the temporary as `path` by
// the steps above. The temporary sits in the same folder (a rename never
// crosses file systems) and keeps `path`'s extension (OpenImageIO picks
// formats by it). If `write` or any step throws, the temporary is removed
// and the exception goes on.
void write_file_durably(const std::string& path, const std::function<void(const std::string&)>& write);

// The same for a file that is these bytes.
void write_file_durably(const std::string& path, std::string_view bytes);

// os.replace made durable: fsyncs `source`, renames it to `target` (same file
// system), fsyncs the target's folder and, when another, the source's. On a
// failure before the rename both files are left as they were.
void replace_file_durably(const std::string& source, const std::string& target);

}  // namespace penumbra
