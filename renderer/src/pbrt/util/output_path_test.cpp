// Temporaries of output files (util/output_path.h): named so that a later run can tell a
// stale one (its writer no longer runs on this host) from one being written, and removed on
// an error. The removal on SIGTERM is tested on the pbrt command
// (tests/renderer/test_output_temporaries.py), where the signal can end a whole process.
#include <pbrt/test_tempdir.h>
#include <pbrt/util/output_path.h>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <stdexcept>
#include <string>

using namespace pbrt;
using namespace pbrt::testing_util;

namespace {

std::string Host() {
    char buf[256] = {};
    gethostname(buf, sizeof buf - 1);
    return buf;
}

// The pid of a process that has ended (reaped): no process has it, for now.
long DeadPid() {
    pid_t child = fork();
    if (child == 0) _exit(0);
    int status = 0;
    waitpid(child, &status, 0);
    return long(child);
}

}  // namespace

TEST(OutputPath, StaleTemporariesOfThisHostAreRemovedOthersKept) {
    TempDir dir;
    const std::string out = dir.File("out.exr");
    const std::string stale = TemporaryPath(out, DeadPid(), Host());
    const std::string running = TemporaryPath(out, long(getpid()), Host());
    const std::string otherHost = TemporaryPath(out, DeadPid(), Host() + "-elsewhere");
    const std::string otherFile = TemporaryPath(dir.File("other.exr"), DeadPid(), Host());
    for (const std::string &f : {stale, running, otherHost, otherFile}) dir.Write(std::filesystem::path(f).filename(), "x");
    EXPECT_EQ(std::filesystem::path(stale).filename().string().rfind("out.exr.pbrt-tmp-", 0), 0u) << stale;
    CheckOutputImagePath(out);  // what pbrt does before it parses the scene
    EXPECT_FALSE(std::filesystem::exists(stale));
    EXPECT_TRUE(std::filesystem::exists(running));
    EXPECT_TRUE(std::filesystem::exists(otherHost));
    EXPECT_TRUE(std::filesystem::exists(otherFile));
    // The same for other output files (--emission-spectrum, --material-reflectances).
    const std::string spd = dir.File("e.spd");
    const std::string staleSpd = TemporaryPath(spd, DeadPid(), Host());
    dir.Write(std::filesystem::path(staleSpd).filename(), "x");
    CheckOutputFilePath(spd);
    EXPECT_FALSE(std::filesystem::exists(staleSpd));
}

TEST(OutputPath, TemporaryIsRemovedUnlessCommitted) {
    TempDir dir;
    const std::string out = dir.File("out.png");
    std::string tmp;
    try {
        TemporaryOutput t(out);
        tmp = t.Path();
        dir.Write(std::filesystem::path(tmp).filename(), "partial");
        throw std::runtime_error("the write failed");
    } catch (const std::runtime_error &) {
    }
    EXPECT_FALSE(std::filesystem::exists(tmp)) << tmp;
    EXPECT_FALSE(std::filesystem::exists(out));
    {
        TemporaryOutput t(out);
        dir.Write(std::filesystem::path(t.Path()).filename(), "whole");
        EXPECT_TRUE(t.Commit());
        tmp = t.Path();
    }
    EXPECT_FALSE(std::filesystem::exists(tmp));
    EXPECT_TRUE(std::filesystem::exists(out));
}
