// Colour management through OpenColorIO.
//
// Every tool works in the config's scene-linear role. Input images arrive in
// some named colour space (an sRGB PNG, an ACEScg EXR, a "Linear Rec.709"
// HDR) and are converted to scene-linear here; outputs can be converted back
// to a display space before writing 8/16-bit files.
//
// Which config: an explicit path wins; otherwise $OCIO. Inside Blender the
// add-on passes Blender's own config (datafiles/colormanagement/config.ocio),
// so names match what the user sees in Blender's colour space menus. There is
// no silent fallback to a built-in config: a wrong config gives wrong colour.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "common/progress.hpp"
#include "image/image.hpp"

namespace penumbra {

class ColorConfig {
public:
    // Loads `path`, or $OCIO when `path` is empty. Throws Error saying which
    // file failed and how to point at a valid one.
    static ColorConfig load(const std::string& path = "");

    const std::string& path() const { return path_; }
    std::vector<std::string> colorspace_names() const;
    // The colour space the scene_linear role points at (e.g. "Linear Rec.709").
    std::string scene_linear() const;
    // True for a colour space name, alias or role the config knows.
    bool has_colorspace(const std::string& name) const;

    // In place, RGB images only. Throws Error listing the valid names when a
    // name is unknown. Reports progress per band of rows (interval: 64 rows).
    void to_scene_linear(Image& image, const std::string& from_space,
                         const Progress& progress = Progress()) const;
    void from_scene_linear(Image& image, const std::string& to_space,
                           const Progress& progress = Progress()) const;
    void convert(Image& image, const std::string& from_space, const std::string& to_space,
                 const Progress& progress = Progress()) const;

    std::string version() const;  // OpenColorIO library version

private:
    struct Impl;
    std::shared_ptr<const Impl> impl_;
    std::string path_;
};

}  // namespace penumbra
