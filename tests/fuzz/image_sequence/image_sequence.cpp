// Fuzz harness: numbered image sequences, core/image/frame_source.cpp. The
// outside data here are the file names in a folder: find_sequence parses the
// frame number out of each, and open_frames picks single image, sequence or
// video from the name and reads frames through the sequence.
//
// Input: one file name per line (at most 64; '/' and NUL dropped, at most
// 120 bytes each). The folder gets each named file; what is in it depends on
// a hash of the name: a 2x1 PNG, a 1x2 PNG (a frame of another size), an
// empty file or bytes that are no image. The first line is the path the user
// picked. Checked: only penumbra::Error; a sequence found is in strictly
// ascending frame order, starts at the picked frame and names existing files.
#include <filesystem>
#include <functional>

#include "../fuzz_util.hpp"
#include "image/frame_source.hpp"
#include "image/image_io.hpp"
#include "image/video.hpp"

using namespace penumbra;
namespace fs = std::filesystem;

namespace {

// The two small PNGs every input copies from, made once per process.
struct Templates {
    std::string wide, tall;
    Templates() {
        const fs::path dir = fs::temp_directory_path() / ("penumbra-fuzz-templates-" + std::to_string(::getpid()));
        fs::create_directories(dir);
        wide = (dir / "wide.png").string();
        tall = (dir / "tall.png").string();
        Image a(2, 1, 3), b(1, 2, 3);
        for (auto& v : a.pixels) v = 0.5f;
        for (auto& v : b.pixels) v = 0.25f;
        write_png16(wide, a, "");
        write_png16(tall, b, "");
        std::atexit([] {
            std::error_code ec;
            fs::remove_all(fs::path(get().wide).parent_path(), ec);
        });
    }
    static Templates& get() {
        static Templates* t = new Templates;
        return *t;
    }
};

}  // namespace

// A name with a video extension opens as a video: `false` stands in for
// ffmpeg (video has harnesses of its own), so each input stays fast.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
    set_ffmpeg_executable("false");
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const Templates& templates = Templates::get();
    const fs::path dir = fuzz::Scratch::get().fresh();
    std::vector<std::string> names;
    std::string current;
    for (std::size_t i = 0; i <= size && names.size() < 64; ++i) {
        const char c = i < size ? char(data[i]) : '\n';
        if (c == '\n') {
            if (!current.empty() && current != "." && current != "..") names.push_back(current);
            current.clear();
        } else if (c != '/' && c != '\0' && current.size() < 120) {
            current += c;
        }
    }
    if (names.empty()) return 0;
    for (const auto& name : names) {
        const fs::path path = dir / name;
        std::error_code ec;
        if (fs::exists(path, ec)) continue;
        switch (std::hash<std::string>{}(name) % 4) {
            case 0: fs::copy_file(templates.wide, path, ec); break;
            case 1: fs::copy_file(templates.tall, path, ec); break;
            case 2: fuzz::write_file(path.string(), "", 0); break;
            default: fuzz::write_file(path.string(), "not an image", 12); break;
        }
    }
    const std::string first = (dir / names.front()).string();

    fuzz::expect_only_penumbra_errors([&] {
        const SequenceFiles files = find_sequence(first);
        penumbra_fuzz_check(!files.paths.empty() && files.paths.size() == files.numbers.size(),
                            "find_sequence returned paths and numbers of different lengths");
        penumbra_fuzz_check(fs::equivalent(files.paths.front(), first), "a sequence does not start at the picked frame");
        for (std::size_t i = 0; i < files.paths.size(); ++i) {
            penumbra_fuzz_check(fs::exists(files.paths[i]), "find_sequence named a file that does not exist");
            if (i) penumbra_fuzz_check(files.numbers[i - 1] < files.numbers[i], "sequence numbers not ascending");
        }
    });
    for (auto kind : {FrameSourceKind::automatic, FrameSourceKind::sequence, FrameSourceKind::single_image}) {
        fuzz::expect_only_penumbra_errors([&] {
            const auto source = open_frames(first, kind);
            const int n = source->frame_count();
            penumbra_fuzz_check(n >= 1, "a frame source with no frames");
            for (int index : {0, n - 1}) {
                const Image image = source->read(index);
                penumbra_fuzz_check(image.width == source->width() && image.height == source->height(),
                                    "a frame's size differs from the source's");
            }
            source->describe();
        });
    }
    return 0;
}
