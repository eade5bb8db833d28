// Opening inputs: only regular files are read, up to a cap; checked size arithmetic.
#include "util/checked_size.h"
#include "util/error.h"
#include "util/file_check.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sys/stat.h>

namespace {

// Calls f, which must throw et::Error: one line, naming `path`, containing `what`.
template <typename F> void expect_error(F&& f, const std::string& path, const std::string& what) {
    try {
        f();
        ADD_FAILURE() << path << ": no error, expected '" << what << "'";
    } catch (const et::Error& e) {
        const std::string m = e.what();
        EXPECT_EQ(m.find('\n'), std::string::npos) << m;
        EXPECT_EQ(m.rfind(path, 0), 0u) << "does not start with the file: " << m;
        EXPECT_NE(m.find(what), std::string::npos) << m;
    }
}

TEST(FileCheck, ReadsRegularFiles) {
    const std::string dir = ett::scratch_dir("file-check");
    std::ofstream(dir + "/a.txt") << "hello";
    EXPECT_EQ(et::check_regular_file(dir + "/a.txt", 100, "text"), 5u);
    EXPECT_EQ(et::read_regular_file(dir + "/a.txt", 100, "text"), "hello");
    std::ofstream(dir + "/empty.txt");
    EXPECT_EQ(et::read_regular_file(dir + "/empty.txt", 100, "text"), "");
    // Through a symbolic link: what it points at counts.
    std::remove((dir + "/link.txt").c_str());
    ASSERT_EQ(symlink((dir + "/a.txt").c_str(), (dir + "/link.txt").c_str()), 0);
    EXPECT_EQ(et::read_regular_file(dir + "/link.txt", 100, "text"), "hello");
}

// Text in UTF-16 or UTF-32 (with or without a byte order mark) is an error naming the encoding;
// a UTF-8 byte order mark is dropped; binary that merely holds NULs is passed on.
TEST(FileCheck, TextFilesNameTheirWideEncoding) {
    const std::string dir = ett::scratch_dir("file-check-text");
    auto write = [&](const std::string& name, const std::string& bytes) {
        std::ofstream(dir + "/" + name, std::ios::binary) << bytes;
        return dir + "/" + name;
    };
    const std::string le = write("le.obj", std::string("\xFF\xFEv\0 \0"
                                                       "0\0",
                                                       8));
    expect_error(
        [&] { et::read_text_file(le, 100, "OBJ file"); }, le,
        "the OBJ file is UTF-16LE text; save it as UTF-8 (or ASCII), e.g. iconv -f UTF-16LE");
    const std::string be = write("be.obj", std::string("\xFE\xFF\0v\0 ", 6));
    expect_error([&] { et::read_text_file(be, 100, "OBJ file"); }, be, "UTF-16BE");
    const std::string u32 = write("u32.json", std::string("\xFF\xFE\0\0{\0\0\0", 8));
    expect_error([&] { et::read_text_file(u32, 100, "scene file"); }, u32, "UTF-32LE");
    const std::string nobom = write("nobom.obj", std::string("v\0 \0"
                                                             "0\0",
                                                             6));
    expect_error([&] { et::read_text_file(nobom, 100, "OBJ file"); }, nobom, "UTF-16LE");
    const std::string nobom_be = write("nobom_be.obj", std::string("\0v\0 \0"
                                                                   "0",
                                                                   6));
    expect_error([&] { et::read_text_file(nobom_be, 100, "OBJ file"); }, nobom_be, "UTF-16BE");
    EXPECT_EQ(et::read_text_file(write("bom.obj", "\xEF\xBB\xBFv 0 0 0\n"), 100, "OBJ file"),
              "v 0 0 0\n");
    const std::string gz("\x1f\x8b\x08\x00\x00\x00", 6); // not text, but not wide text either
    EXPECT_EQ(et::read_text_file(write("gz.obj", gz), 100, "OBJ file"), gz);
}

TEST(FileCheck, RefusesEverythingElseWithoutBlocking) {
    const std::string dir = ett::scratch_dir("file-check-bad");
    // A FIFO with no writer: opening it for reading would block forever.
    ASSERT_EQ(mkfifo((dir + "/fifo").c_str(), 0600), 0);
    expect_error([&] { et::read_regular_file(dir + "/fifo", 100, "scene file"); }, dir + "/fifo",
                 "FIFO");
    expect_error([&] { et::read_regular_file("/dev/zero", 1 << 20, "map"); }, "/dev/zero",
                 "character device");
    expect_error([&] { et::read_regular_file("/dev/urandom", 1 << 20, "mesh"); }, "/dev/urandom",
                 "not a regular file");
    expect_error([&] { et::check_regular_file(dir, 100, "map"); }, dir, "folder");
    expect_error([&] { et::read_regular_file(dir + "/missing", 100, "map"); }, dir + "/missing",
                 "no such file");
    // A link to a FIFO is a FIFO.
    ASSERT_EQ(symlink((dir + "/fifo").c_str(), (dir + "/fifo-link").c_str()), 0);
    expect_error([&] { et::read_regular_file(dir + "/fifo-link", 100, "map"); }, dir + "/fifo-link",
                 "FIFO");
}

TEST(FileCheck, SizeCap) {
    const std::string dir = ett::scratch_dir("file-check-cap");
    std::ofstream(dir + "/big.txt") << std::string(1000, 'x');
    expect_error([&] { et::read_regular_file(dir + "/big.txt", 999, "scene file"); },
                 dir + "/big.txt", "more than the 999 bytes read at most");
    EXPECT_EQ(et::read_regular_file(dir + "/big.txt", 1000, "scene file").size(), 1000u);
}

TEST(CheckedSize, OverflowIsAnError) {
    EXPECT_EQ(et::checked_mul(65536, 65536, "x"), uint64_t(1) << 32);
    EXPECT_THROW(et::checked_mul(uint64_t(1) << 33, uint64_t(1) << 31, "x"), et::Error);
    EXPECT_THROW(et::checked_add(~uint64_t(0), 1, "x"), et::Error);
}

} // namespace
