// Numbered image sequences (image/frame_source.hpp): found in order from any
// frame, with gaps and size changes reported by frame.
#include "image/frame_source.hpp"

#include <cstdio>

#include "common/error.hpp"
#include "image/image_io.hpp"
#include "image_test_util.hpp"
#include "test_files.hpp"

namespace penumbra {
namespace {

using testing::flat;
using testing::ScratchDir;

void write_sequence(const ScratchDir& dir, const std::vector<int>& numbers, int w = 8, int h = 4) {
    for (int n : numbers) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%04d.exr", n);
        write_exr(dir.file(name), flat(w, h, 0.1f * n), ExrPrecision::full, "");
    }
}

TEST(FrameSource, numbered_sequence_is_found_in_order_from_its_first_frame) {
    ScratchDir dir;
    write_sequence(dir, {3, 4, 5, 6});
    testing::write_bytes(dir.file("other_0001.exr"), "unrelated");
    const SequenceFiles files = find_sequence(dir.file("frame_0003.exr"));
    ASSERT_EQ(files.numbers, (std::vector<int>{3, 4, 5, 6}));
    auto source = open_frames(dir.file("frame_0003.exr"));
    ASSERT_EQ(source->frame_count(), 4);
    EXPECT_NEAR(source->read(2).pixels[0], 0.5f, 1e-6);
}

TEST(FrameSource, starting_mid_sequence_skips_earlier_frames) {
    ScratchDir dir;
    write_sequence(dir, {1, 2, 3});
    EXPECT_EQ(find_sequence(dir.file("frame_0002.exr")).numbers, (std::vector<int>{2, 3}));
}

TEST(FrameSource, missing_frame_in_a_sequence_is_an_error_naming_it) {
    ScratchDir dir;
    write_sequence(dir, {1, 2, 4, 5});
    try {
        find_sequence(dir.file("frame_0001.exr"));
        FAIL() << "a gap in the sequence went unnoticed";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("frame_0003.exr"), std::string::npos) << e.what();
    }
}

TEST(FrameSource, sequence_whose_frames_change_size_is_an_error_at_that_frame) {
    ScratchDir dir;
    write_sequence(dir, {1, 2});
    write_exr(dir.file("frame_0003.exr"), flat(16, 4, 1.0f), ExrPrecision::full, "");
    auto source = open_frames(dir.file("frame_0001.exr"), FrameSourceKind::sequence);
    EXPECT_NO_THROW(source->read(1));
    try {
        source->read(2);
        FAIL();
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("16x4"), std::string::npos) << e.what();
    }
}

TEST(FrameSource, single_numbered_file_without_neighbours_is_a_single_image) {
    ScratchDir dir;
    write_sequence(dir, {7});
    EXPECT_EQ(open_frames(dir.file("frame_0007.exr"))->frame_count(), 1);
}

}  // namespace
}  // namespace penumbra
