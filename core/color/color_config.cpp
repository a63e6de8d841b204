#include "color/color_config.hpp"

#include <OpenColorIO/OpenColorIO.h>

#include <cstdlib>
#include <filesystem>

#include "common/error.hpp"

namespace penumbra {

namespace OCIO = OCIO_NAMESPACE;

struct ColorConfig::Impl {
    OCIO::ConstConfigRcPtr config;
};

ColorConfig ColorConfig::load(const std::string& path) {
    std::string chosen = path;
    if (chosen.empty()) {
        const char* env = std::getenv("OCIO");
        if (!env || !*env)
            throw Error("no OpenColorIO config: pass the path of a config.ocio (Blender's is "
                        "<blender>/datafiles/colormanagement/config.ocio) or set $OCIO");
        chosen = env;
    }
    std::error_code ec;
    if (!std::filesystem::is_regular_file(chosen, ec))
        throw Error("OpenColorIO config '" + chosen + "' not found; check the path or $OCIO");
    ColorConfig result;
    try {
        auto impl = std::make_shared<Impl>();
        impl->config = OCIO::Config::CreateFromFile(chosen.c_str());
        impl->config->validate();
        result.impl_ = std::move(impl);
    } catch (const OCIO::Exception& e) {
        throw Error("OpenColorIO config '" + chosen + "' cannot be used: " + e.what() +
                    " (OpenColorIO " + OCIO::GetVersion() + "); point at a config this version can read");
    }
    result.path_ = chosen;
    return result;
}

std::vector<std::string> ColorConfig::colorspace_names() const {
    std::vector<std::string> names;
    const auto& cfg = impl_->config;
    for (int i = 0; i < cfg->getNumColorSpaces(); ++i)
        names.emplace_back(cfg->getColorSpaceNameByIndex(i));
    return names;
}

bool ColorConfig::has_colorspace(const std::string& name) const {
    return !name.empty() && impl_->config->getColorSpace(name.c_str()) != nullptr;
}

std::string ColorConfig::scene_linear() const {
    auto cs = impl_->config->getColorSpace(OCIO::ROLE_SCENE_LINEAR);
    if (!cs)
        throw Error("OpenColorIO config '" + path_ + "' has no scene_linear role; use a config that defines it");
    return cs->getName();
}

std::string ColorConfig::version() const { return OCIO::GetVersion(); }

void ColorConfig::convert(Image& image, const std::string& from_space, const std::string& to_space,
                          const Progress& progress) const {
    for (const std::string* name : {&from_space, &to_space}) {
        if (!has_colorspace(*name)) {
            std::string list;
            for (const auto& n : colorspace_names())
                list += (list.empty() ? "" : ", ") + ("'" + n + "'");
            throw ArgumentError("unknown colour space '" + *name + "' in OpenColorIO config '" + path_ +
                                "'; valid names are: " + list);
        }
    }
    if (image.channels != 3)
        throw ArgumentError("colour conversion needs an RGB image, got " + std::to_string(image.channels) +
                            " channels");
    OCIO::ConstCPUProcessorRcPtr cpu;
    try {
        cpu = impl_->config->getProcessor(from_space.c_str(), to_space.c_str())->getDefaultCPUProcessor();
    } catch (const OCIO::Exception& e) {
        throw Error("cannot convert '" + from_space + "' to '" + to_space + "': " + e.what());
    }
    // Work on a copy so a cancelled conversion leaves the caller's image as it was.
    Image converted = image;
    constexpr int band = 64;
    for (int y0 = 0; y0 < image.height; y0 += band) {
        progress.report(double(y0) / image.height);
        const int rows = std::min(band, image.height - y0);
        OCIO::PackedImageDesc desc(converted.row(y0), image.width, rows, 3);
        cpu->apply(desc);
    }
    progress.report(1.0);
    image = std::move(converted);
}

void ColorConfig::to_scene_linear(Image& image, const std::string& from_space, const Progress& progress) const {
    convert(image, from_space, scene_linear(), progress);
}

void ColorConfig::from_scene_linear(Image& image, const std::string& to_space, const Progress& progress) const {
    convert(image, scene_linear(), to_space, progress);
}

}  // namespace penumbra
