// The one atomic-write helper: a file appears under its final name whole, or not at all.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <sys/stat.h>
#include <unistd.h>

#include "render_test_util.hpp"
#include "simreel/render/atomic_file.hpp"
#include "simreel/render/image.hpp"

namespace simreel::render {
namespace {

namespace fs = std::filesystem;

std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST(RenderAtomicFile, CommittedFileHasTheBytesAndNoTemporaryIsLeft) {
  const test::TempDir dir("atomic-commit");
  const fs::path path = dir.path() / "sub" / "a.bin";  // the parent is created
  const std::string bytes("line one\n\0binary\xff", 17);
  {
    AtomicFile f(path);
    EXPECT_EQ(f.path(), path);
    EXPECT_EQ(f.temporary().parent_path(), path.parent_path());
    EXPECT_TRUE(fs::exists(f.temporary()));
    EXPECT_FALSE(fs::exists(path));
    f.write(bytes.substr(0, 5));
    f.write(bytes.substr(5));
    f.commit();
    EXPECT_FALSE(fs::exists(f.temporary()));
  }
  EXPECT_EQ(read_all(path), bytes);
  EXPECT_EQ(std::distance(fs::directory_iterator(path.parent_path()), fs::directory_iterator()), 1);

  write_file_atomic(dir.path() / "b.txt", "hello");
  EXPECT_EQ(read_all(dir.path() / "b.txt"), "hello");
}

TEST(RenderAtomicFile, DestroyedWithoutCommitLeavesNothing) {
  const test::TempDir dir("atomic-discard");
  fs::path tmp;
  {
    AtomicFile f(dir.path() / "a.bin");
    f.write("partial");
    tmp = f.temporary();
    EXPECT_TRUE(fs::exists(tmp));
  }
  EXPECT_FALSE(fs::exists(tmp));
  EXPECT_EQ(dir.entries(), 0);

  AtomicFile f(dir.path() / "b.bin");
  f.discard();
  EXPECT_EQ(f.file(), nullptr);
  EXPECT_EQ(dir.entries(), 0);
}

TEST(RenderAtomicFile, UncreatableDirectoryThrowsNamingThePathAndLeavesNothing) {
  const test::TempDir dir("atomic-nodir");
  // A regular file where a directory is needed: create_directories cannot make it.
  std::ofstream(dir.path() / "blocker") << "x";
  const fs::path path = dir.path() / "blocker" / "sub" / "a.png";
  for (int writer = 0; writer < 3; ++writer) {
    try {
      if (writer == 0) { AtomicFile f(path); }
      if (writer == 1) write_file_atomic(path, "bytes");
      if (writer == 2) write_png(path, Image(2, 2));
      FAIL() << "writer " << writer << " did not throw";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
    }
  }
  EXPECT_EQ(dir.entries(), 1);  // the blocker alone
  EXPECT_EQ(read_all(dir.path() / "blocker"), "x");
}

TEST(RenderAtomicFile, ExistingFileIsReplacedOnlyAtCommit) {
  const test::TempDir dir("atomic-replace");
  const fs::path path = dir.path() / "golden.json";
  write_file_atomic(path, "old content");
  {
    AtomicFile f(path);
    f.write("new content, longer than the old");
    EXPECT_EQ(read_all(path), "old content");  // a reader still sees the whole old file
    f.commit();
  }
  EXPECT_EQ(read_all(path), "new content, longer than the old");
  {
    AtomicFile f(path);
    f.write("abandoned");
  }  // not committed: the previous file stays
  EXPECT_EQ(read_all(path), "new content, longer than the old");
  EXPECT_EQ(dir.entries(), 1);
}

TEST(RenderAtomicFile, AFifoOrFolderIsRefusedAndLeftAsItWas) {
  // The rename over the final name replaced whatever was there: as root, `--hash /dev/full`
  // turned the device into a JSON file. A FIFO stands in for the device here.
  const test::TempDir dir("atomic-special");
  const fs::path fifo = dir.path() / "pipe.csv";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  try {
    AtomicFile f(fifo);
    ADD_FAILURE() << "a FIFO was accepted as the final name";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("pipe.csv: is a FIFO, expected a regular file"), std::string::npos) << e.what();
  }
  EXPECT_EQ(fs::status(fifo).type(), fs::file_type::fifo);
  fs::create_directory(dir.path() / "folder");
  EXPECT_THROW(write_file_atomic(dir.path() / "folder", "x"), IoError);
  EXPECT_TRUE(fs::is_directory(dir.path() / "folder"));
  EXPECT_EQ(dir.entries(), 2);  // no temporary left
  EXPECT_EQ(unreplaceable_output(dir.path() / "new.json"), "");
  EXPECT_EQ(file_kind(dir.path() / "folder"), "a directory");
}

TEST(RenderAtomicFile, ALinkToAFileIsWrittenThroughAndKept) {
  const test::TempDir dir("atomic-link");
  const fs::path real = dir.path() / "real.json", link = dir.path() / "link.json";
  write_file_atomic(real, "old");
  fs::create_symlink("real.json", link);
  write_file_atomic(link, "new");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(read_all(real), "new");
  EXPECT_EQ(dir.entries(), 2);
}

TEST(RenderAtomicFile, CommitTwiceThrows) {
  const test::TempDir dir("atomic-twice");
  AtomicFile f(dir.path() / "a.bin");
  f.commit();
  EXPECT_THROW(f.commit(), IoError);
  EXPECT_TRUE(fs::exists(dir.path() / "a.bin"));
}

TEST(RenderAtomicFile, PngWrittenThroughItLeavesOnlyTheFile) {
  const test::TempDir dir("atomic-png");
  Image img(3, 2);
  for (std::size_t i = 0; i < img.rgba.size(); ++i) img.rgba[i] = std::uint8_t(i * 7);
  write_png(dir.path() / "frames" / "f.png", img);
  EXPECT_EQ(read_image(dir.path() / "frames" / "f.png").rgba, img.rgba);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path() / "frames"), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace simreel::render
