// Write-to-temporary-then-rename, the only way Penumbra creates files.
#pragma once

#include <functional>
#include <string>

namespace penumbra {

// Calls `write(temporary_path)`, then renames the temporary over `path`.
// The temporary sits in the same folder (a rename never crosses file
// systems) and keeps `path`'s extension (OpenImageIO picks formats by it).
// If `write` throws, the temporary is removed and the exception goes on;
// `path` is never left half-written.
void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write);

}  // namespace penumbra
