// Outputs written all-or-nothing (host/lib/util/output_batch.h): nothing reaches a target before
// commit; an abandoned batch leaves neither targets nor temporaries; inputs of the run, folders,
// missing folders and two names of one file are refused before anything is written; stale
// temporaries of dead processes are removed, those of live ones kept.
#include "util/output_batch.h"
#include "util/error.h"
#include "util/file_check.h"
#include "test_data.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <fcntl.h>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sys/file.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

void put(const std::string& path, const std::string& text) {
    std::ofstream(path, std::ios::binary) << text;
}
std::string get(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
size_t entries(const std::string& dir) {
    return static_cast<size_t>(
        std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}
auto writes(const std::string& text) {
    return [text](const std::string& tmp) { put(tmp, text); };
}
using ett::error_of;

TEST(OutputBatch, NothingReachesATargetBeforeCommit) {
    const std::string dir = ett::scratch_dir("batch_commit");
    put(dir + "/a.exr", "old a");
    put(dir + "/b.png", "old b");
    {
        et::OutputBatch batch({dir + "/a.exr", dir + "/b.png"});
        batch.write(dir + "/a.exr", writes("new a"));
        EXPECT_EQ(get(dir + "/a.exr"), "old a");
        batch.write(dir + "/b.png", writes("new b"));
        EXPECT_EQ(get(dir + "/b.png"), "old b");
        batch.commit();
    }
    EXPECT_EQ(get(dir + "/a.exr"), "new a");
    EXPECT_EQ(get(dir + "/b.png"), "new b");
    EXPECT_EQ(entries(dir), 2u) << "a temporary was left";
}

// Two processes committing outputs of the same names: each batch renames its files with the
// folders locked (flock), so one set lands whole after the other, never a mix. A lock held here
// on the folder stands for the other process: the commit waits until it is released.
TEST(OutputBatch, CommitWaitsForAnotherCommitToTheSameFolder) {
    const std::string dir = ett::scratch_dir("batch_lock");
    et::OutputBatch b({dir + "/a.exr", dir + "/a.png"});
    b.write(dir + "/a.exr", writes("new a"));
    b.write(dir + "/a.png", writes("new png"));
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX), 0);
    std::atomic<bool> done{false};
    std::thread commit([&] {
        b.commit();
        done = true;
    });
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    EXPECT_FALSE(done.load()) << "committed while the folder was locked";
    EXPECT_FALSE(fs::exists(dir + "/a.exr"));
    ::close(fd); // the other commit ends
    commit.join();
    EXPECT_TRUE(done.load());
    EXPECT_EQ(get(dir + "/a.exr"), "new a");
    EXPECT_EQ(get(dir + "/a.png"), "new png");
}

TEST(OutputBatch, AFailingWriterLeavesEveryOldOutput) {
    const std::string dir = ett::scratch_dir("batch_abandon");
    put(dir + "/a.exr", "old a");
    put(dir + "/b.png", "old b");
    const std::string e = error_of([&] {
        et::OutputBatch batch({dir + "/a.exr", dir + "/b.png", dir + "/c.json"});
        batch.write(dir + "/a.exr", writes("new a"));
        batch.write(dir + "/b.png", [](const std::string&) { throw et::Error("b: disk full"); });
        batch.commit();
    });
    EXPECT_EQ(e, "b: disk full");
    EXPECT_EQ(get(dir + "/a.exr"), "old a");
    EXPECT_EQ(get(dir + "/b.png"), "old b");
    EXPECT_FALSE(fs::exists(dir + "/c.json"));
    EXPECT_EQ(entries(dir), 2u) << "a temporary was left";
    // A commit with a target not written is a bug, and writes nothing either.
    EXPECT_NE(error_of([&] {
                  et::OutputBatch batch({dir + "/a.exr", dir + "/b.png"});
                  batch.write(dir + "/a.exr", writes("new a"));
                  batch.commit();
              }).find("b.png"),
              std::string::npos);
    EXPECT_EQ(get(dir + "/a.exr"), "old a");
    EXPECT_EQ(entries(dir), 2u);
}

// A rename that fails after others have been made (here the second file's temporary is gone;
// a target turned into a folder mid-run did it before) puts the ones made back: every previous
// output as it was, a new name removed again.
TEST(OutputBatch, AFailedRenameLeavesEveryOldOutput) {
    const std::string dir = ett::scratch_dir("batch_rename_fails");
    put(dir + "/a.exr", "old a");
    put(dir + "/c.json", "old c");
    const std::string e = error_of([&] {
        et::OutputBatch batch({dir + "/a.exr", dir + "/b.png", dir + "/c.json"});
        batch.write(dir + "/a.exr", writes("new a"));
        batch.write(dir + "/b.png", writes("new b"));
        batch.write(dir + "/c.json", writes("new c"));
        fs::remove(et::temporary_path(dir + "/c.json", ::getpid()));
        batch.commit();
    });
    EXPECT_NE(e.find("c.json: cannot write"), std::string::npos) << e;
    EXPECT_EQ(get(dir + "/a.exr"), "old a");
    EXPECT_FALSE(fs::exists(dir + "/b.png"));
    EXPECT_EQ(get(dir + "/c.json"), "old c");
    EXPECT_EQ(entries(dir), 2u) << "a temporary or a kept file was left";
    // A target that became a folder after the batch was made: refused before anything moves.
    const std::string e2 = error_of([&] {
        et::OutputBatch batch({dir + "/a.exr", dir + "/d.png"});
        batch.write(dir + "/a.exr", writes("new a"));
        batch.write(dir + "/d.png", writes("new d"));
        fs::create_directory(dir + "/d.png");
        batch.commit();
    });
    EXPECT_NE(e2.find("d.png: cannot write: it is a folder"), std::string::npos) << e2;
    EXPECT_EQ(get(dir + "/a.exr"), "old a");
}

// Names too long for a temporary's are cut, and two targets that differ only past the cut had
// one temporary: the second write replaced the first's, and the first output got its bytes.
TEST(OutputBatch, LongNamesGetDistinctTemporaries) {
    const std::string dir = ett::scratch_dir("batch_long_names");
    const std::string stem(238, 'A');
    const std::string a = dir + "/" + stem + "_1.png", b = dir + "/" + stem + "_2.png";
    EXPECT_NE(et::temporary_path(a, 123), et::temporary_path(b, 123));
    EXPECT_LE(fs::path(et::temporary_path(a, 4294967)).filename().string().size(), 255u);
    {
        et::OutputBatch batch({a, b});
        batch.write(a, writes("one"));
        batch.write(b, writes("two"));
        batch.commit();
    }
    EXPECT_EQ(get(a), "one");
    EXPECT_EQ(get(b), "two");
    EXPECT_EQ(entries(dir), 2u);
}

TEST(OutputBatch, RefusesInputsFoldersAndTwins) {
    const std::string dir = ett::scratch_dir("batch_refuse");
    put(dir + "/map.exr", "texels");
    et::check_regular_file(dir + "/map.exr", et::kGiB, "environment map"); // as every reader does
    // The input itself, under another spelling, and through a hard link.
    for (const std::string& t : {dir + "/map.exr", dir + "/./map.exr", dir + "/link.exr"}) {
        if (t == dir + "/link.exr")
            fs::create_hard_link(dir + "/map.exr", t);
        const std::string e = error_of([&] { et::OutputBatch b({dir + "/out.png", t}); });
        EXPECT_NE(e.find("an input of this run"), std::string::npos) << t << ": " << e;
        EXPECT_NE(e.find("map.exr"), std::string::npos) << e;
    }
    // ... unless the caller says it may be replaced (a render state continuing itself).
    EXPECT_EQ(error_of([&] { et::OutputBatch b({dir + "/map.exr"}, {dir + "/map.exr"}); }), "");
    // Two targets that are one file; a folder; a missing folder; an empty name.
    EXPECT_NE(error_of([&] {
                  et::OutputBatch b({dir + "/x.exr",
                                     dir + "/../" + fs::path(dir).filename().string() + "/x.exr"});
              }).find("same file"),
              std::string::npos);
    fs::create_directories(dir + "/folder.exr");
    EXPECT_NE(error_of([&] { et::OutputBatch b({dir + "/folder.exr"}); }).find("is a folder"),
              std::string::npos);
    EXPECT_NE(error_of([&] { et::OutputBatch b({dir + "/none/x.exr"}); }).find("does not exist"),
              std::string::npos);
    EXPECT_NE(error_of([&] { et::OutputBatch b({""}); }), "");
    EXPECT_EQ(get(dir + "/map.exr"), "texels");
}

TEST(OutputBatch, StaleTemporariesOfDeadProcessesAreRemoved) {
    const std::string dir = ett::scratch_dir("batch_stale");
    // A process that has ended: its pid is free (until reused, which the test cannot see).
    const pid_t child = fork();
    if (child == 0)
        _exit(0);
    waitpid(child, nullptr, 0);
    const std::string dead = et::temporary_path(dir + "/out.exr", child);
    const std::string live = et::temporary_path(dir + "/out.exr", getppid());
    const std::string other = et::temporary_path(dir + "/other.exr", child);
    EXPECT_EQ(dead, dir + "/.out.tmp" + std::to_string(child) + ".exr");
    put(dead, "half");
    put(dead + ".previous", "an old output a killed commit kept aside");
    put(live + ".previous", "kept aside by a commit in progress");
    put(live, "in progress elsewhere");
    put(other, "not ours");
    put(dir + "/.out.tmpabc.exr", "not a pid");
    {
        et::OutputBatch batch({dir + "/out.exr"});
        EXPECT_FALSE(fs::exists(dead));
        EXPECT_FALSE(fs::exists(dead + ".previous"));
        EXPECT_TRUE(fs::exists(live));
        EXPECT_TRUE(fs::exists(live + ".previous"));
        EXPECT_TRUE(fs::exists(other));
        EXPECT_TRUE(fs::exists(dir + "/.out.tmpabc.exr"));
    }
    EXPECT_FALSE(fs::exists(dir + "/out.exr"));
}

} // namespace
