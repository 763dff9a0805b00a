// No input file may crash, abort or exhaust simreel (issue 15): assimp's own test corpus
// (Debian's assimp-testmodels, installed by .ci/setup.sh) imports cleanly or fails with an
// AssetError; files that are not regular files or exceed the limits are refused by name.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "simreel/assets/mesh.hpp"

namespace fs = std::filesystem;
using simreel::assets::AssetError;
using simreel::assets::load_mesh;

namespace {

const fs::path kCorpus = "/usr/share/assimp/models";

/// Starts a child that imports `file`; it exits 0 when the import succeeded or threw AssetError.
pid_t start_import(const fs::path& file) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::alarm(20);
    int code = 0;
    try {
      (void)load_mesh(file);
    } catch (const AssetError&) {
    } catch (...) {
      code = 3;
    }
    ::_exit(code);
  }
  return pid;
}

/// "" for a clean end, otherwise how the child ended (a crash, an abort, another exception, a
/// hang past 20 s).
std::string how_it_ended(int status) {
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return "";
  if (WIFEXITED(status)) return "an exception other than AssetError";
  return "killed by signal " + std::to_string(WTERMSIG(status));
}

std::string import_in_child(const fs::path& file) {
  const pid_t pid = start_import(file);
  int status = 0;
  ::waitpid(pid, &status, 0);
  return how_it_ended(status);
}

std::string error_of(const fs::path& file) {
  try {
    (void)load_mesh(file);
  } catch (const AssetError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(MeshCorpus, TheFourFilesThatCrashedAssimpAreCleanErrors) {
  ASSERT_TRUE(fs::is_directory(kCorpus)) << kCorpus << ": assimp-testmodels is not installed (.ci/setup.sh installs it)";
  for (const char* name : {"RAW/WithColor.raw", "RAW/WithTexture.raw", "OpenGEX/camera.ogex", "OpenGEX/collada.ogex"}) {
    const fs::path file = kCorpus / name;
    ASSERT_TRUE(fs::exists(file)) << file;
    EXPECT_EQ(import_in_child(file), "") << file;
    const std::string err = error_of(file);
    EXPECT_NE(err.find(file.string()), std::string::npos) << name << " must be refused naming the file: " << err;
  }
}

TEST(MeshCorpus, AFileDeclaringBillionsOfElementsIsBoundedNotImported) {
  const fs::path file = kCorpus / "invalid/OutOfMemory.off";
  ASSERT_TRUE(fs::exists(file)) << file << ": assimp-testmodels is not installed (.ci/setup.sh installs it)";
  EXPECT_EQ(import_in_child(file), "");
  const std::string err = error_of(file);
  EXPECT_NE(err.find(file.string()), std::string::npos) << err;
}

TEST(MeshCorpus, EveryCorpusFileImportsOrFailsCleanly) {
  ASSERT_TRUE(fs::is_directory(kCorpus)) << kCorpus << ": assimp-testmodels is not installed (.ci/setup.sh installs it)";
  const auto start = std::chrono::steady_clock::now();
  std::vector<std::string> bad;
  int files = 0;
  std::map<pid_t, std::string> running;  // four imports at a time keep the test near 10 s
  auto reap_one = [&] {
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid <= 0) return;
    if (std::string how = how_it_ended(status); !how.empty()) bad.push_back(running[pid] + ": " + how);
    running.erase(pid);
  };
  for (const auto& entry : fs::recursive_directory_iterator(kCorpus)) {
    if (!entry.is_regular_file()) continue;
    ++files;
    if (running.size() >= 4) reap_one();
    running[start_import(entry.path())] = entry.path().string();
  }
  while (!running.empty()) reap_one();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_GT(files, 100);
  EXPECT_TRUE(bad.empty()) << bad.size() << " of " << files << " files, first: " << bad.front();
  RecordProperty("seconds", std::to_string(seconds));
}

TEST(MeshLimits, FifoDeviceAndOversizedFilesAreRefusedByName) {
  const fs::path dir = fs::temp_directory_path() / ("simreel-mesh-limits-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path fifo = dir / "pipe.obj";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string err = error_of(fifo);  // would block in open() if read
  EXPECT_NE(err.find("pipe.obj: cannot import mesh: not a regular file"), std::string::npos) << err;
  err = error_of("/dev/zero");
  EXPECT_NE(err.find("/dev/zero: cannot import mesh: not a regular file"), std::string::npos) << err;
  const fs::path big = dir / "big.obj";
  std::ofstream(big) << "v 0 0 0\n";
  fs::resize_file(big, simreel::assets::kMaxMeshFileBytes + 1);  // sparse: no disk used
  err = error_of(big);
  EXPECT_NE(err.find("big.obj"), std::string::npos) << err;
  EXPECT_NE(err.find("expected at most 268435456 (the mesh file size limit)"), std::string::npos) << err;
  fs::remove_all(dir);
}
