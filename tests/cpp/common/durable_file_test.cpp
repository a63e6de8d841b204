// The durable write (common/durable_file.hpp): its steps in order, seen
// through the recording hook of common/fault_injection.hpp, and what an fsync
// that fails (injected as EIO) leaves on disk.
#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "common/durable_file.hpp"
#include "common/error.hpp"
#include "common/fault_injection.hpp"
#include "test_files.hpp"

namespace penumbra {
namespace {

using testing::FsyncFailure;
using Files = std::map<std::string, std::string>;

class DurableFile : public ::testing::Test {
protected:
    void SetUp() override { testing::record_durable_steps(); }
    void TearDown() override {
        testing::inject_fsync_failure(FsyncFailure::none);
        testing::recorded_durable_steps();
    }

    // Every file in the scratch folder, by name, with its contents.
    Files files() const {
        Files out;
        for (const auto& entry : std::filesystem::directory_iterator(scratch.path()))
            out[entry.path().filename().string()] = testing::read_bytes(entry.path().string());
        return out;
    }

    testing::ScratchDir scratch;
};

// The message of the IoError `act` throws ("" if none).
std::string io_error_of(const std::function<void()>& act) {
    try {
        act();
    } catch (const IoError& e) {
        return e.what();
    }
    return "";
}

// Writes "new contents" over a file of "old contents" with `failure`
// injected; returns the error.
std::string write_failing(const std::string& path, FsyncFailure failure) {
    testing::write_bytes(path, "old contents");
    testing::inject_fsync_failure(failure);
    return io_error_of([&] { write_file_durably(path, std::string_view("new contents")); });
}

// "rename <from> -> <to>" → <from>
std::string renamed_from(const std::string& step) {
    const std::string prefix = "rename ";
    return step.substr(prefix.size(), step.find(" -> ") - prefix.size());
}

TEST_F(DurableFile, flushes_the_file_then_renames_it_into_place_then_flushes_the_folder) {
    const std::string path = scratch.file("model.pzh");
    write_file_durably(path, std::string_view("new contents"));
    const auto steps = testing::recorded_durable_steps();
    ASSERT_EQ(steps.size(), 3u);
    ASSERT_EQ(steps[1].rfind("rename ", 0), 0u) << steps[1];
    const std::string temporary = renamed_from(steps[1]);
    EXPECT_NE(temporary, path);
    EXPECT_EQ(std::filesystem::path(temporary).parent_path(), scratch.path());
    EXPECT_EQ(steps[0], "fsync file " + temporary);
    EXPECT_EQ(steps[1], "rename " + temporary + " -> " + path);
    EXPECT_EQ(steps[2], "fsync folder " + scratch.path().string());
    EXPECT_EQ(files(), (Files{{"model.pzh", "new contents"}}));
}

TEST_F(DurableFile, a_failed_file_fsync_raises_and_leaves_the_old_file_and_no_temporary) {
    const std::string path = scratch.file("lookup.exr");
    const std::string error = write_failing(path, FsyncFailure::file);
    EXPECT_NE(error.find("unchanged"), std::string::npos) << error;
    EXPECT_NE(error.find("Input/output error"), std::string::npos) << error;
    EXPECT_EQ(testing::recorded_durable_steps().size(), 1u);  // never renamed
    EXPECT_EQ(files(), (Files{{"lookup.exr", "old contents"}}));
}

TEST_F(DurableFile, a_failed_folder_fsync_raises_after_the_rename_without_a_temporary) {
    const std::string path = scratch.file("rig.json");
    const std::string error = write_failing(path, FsyncFailure::folder);
    EXPECT_NE(error.find("power cut"), std::string::npos) << error;
    EXPECT_EQ(testing::recorded_durable_steps().size(), 3u);
    EXPECT_EQ(files(), (Files{{"rig.json", "new contents"}}));
}

TEST_F(DurableFile, a_failed_write_removes_its_temporary_and_keeps_the_old_file) {
    const std::string path = scratch.file("piece.pvis");
    testing::write_bytes(path, "old contents");
    EXPECT_THROW(write_file_durably(path, [](const std::string& temporary) {
        testing::write_bytes(temporary, "half");
        throw IoError("disk full");
    }), IoError);
    EXPECT_TRUE(testing::recorded_durable_steps().empty());
    EXPECT_EQ(files(), (Files{{"piece.pvis", "old contents"}}));
}

TEST_F(DurableFile, replace_flushes_the_source_then_renames_then_flushes_the_folder) {
    const std::string source = scratch.file("lookup.exr"), target = scratch.file("lookup.exr.penumbra-backup");
    testing::write_bytes(source, "lookup");
    replace_file_durably(source, target);
    EXPECT_EQ(testing::recorded_durable_steps(),
              (std::vector<std::string>{"fsync file " + source, "rename " + source + " -> " + target,
                                        "fsync folder " + scratch.path().string()}));
    EXPECT_EQ(files(), (Files{{"lookup.exr.penumbra-backup", "lookup"}}));
}

TEST_F(DurableFile, a_failed_fsync_before_a_replace_leaves_both_files) {
    const std::string source = scratch.file("backup"), target = scratch.file("lookup.exr");
    testing::write_bytes(source, "old");
    testing::write_bytes(target, "new");
    testing::inject_fsync_failure(FsyncFailure::file);
    EXPECT_THROW(replace_file_durably(source, target), IoError);
    EXPECT_EQ(files(), (Files{{"backup", "old"}, {"lookup.exr", "new"}}));
}

TEST_F(DurableFile, a_missing_folder_is_named_in_the_error) {
    const std::string error = io_error_of([&] { write_file_durably(scratch.file("no/such/model.pzh"), "x"); });
    EXPECT_NE(error.find("no/such' does not exist; create it first"), std::string::npos) << error;
}

}  // namespace
}  // namespace penumbra
