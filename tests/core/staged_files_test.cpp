// StagedFiles: a texture set's files appear together or not at all, and so does the output folder it made for them:
// destroyed before publish_all, it removes what it staged and the folders make_folder created (innermost first, each
// only when empty), keeps folders that were there before, and also removes the levels a creation that failed part
// way had made, wherever a symlink and ".." in the path lead.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <gtest/gtest.h>

#include "test_folder.hpp"
#include "texwarp/core/atomic_file.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;

void write_file(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(StagedFiles, AFailedSetLeavesNeitherItsFilesNorTheFoldersItMade) {
  const testing::TestFolder folder{"staged-files"};
  const fs::path& root = folder.path();
  {
    StagedFiles staged;
    staged.make_folder((root / "out" / "maps" / "").string());  // a trailing separator, as a user may type it
    ASSERT_TRUE(fs::is_directory(root / "out" / "maps"));
    write_file(staged.stage((root / "out" / "maps" / "a.png").string()), "a");
  }  // not published
  EXPECT_FALSE(fs::exists(root / "out"));
  EXPECT_TRUE(fs::is_directory(root));  // there before: kept
}

TEST(StagedFiles, PublishedFilesKeepTheirFoldersAndForeignFilesKeepTheirs) {
  const testing::TestFolder folder{"staged-files"};
  const fs::path& root = folder.path();
  {
    StagedFiles staged;
    staged.make_folder((root / "out" / "maps").string());
    write_file(staged.stage((root / "out" / "maps" / "a.png").string()), "a");
    staged.publish_all();
  }
  EXPECT_TRUE(fs::is_regular_file(root / "out" / "maps" / "a.png"));
  {
    StagedFiles staged;
    staged.make_folder((root / "other" / "maps").string());
    write_file((root / "other" / "note.txt").string(), "someone else's");  // not staged: not the set's
  }
  EXPECT_FALSE(fs::exists(root / "other" / "maps"));  // empty again: removed
  EXPECT_TRUE(fs::is_regular_file(root / "other" / "note.txt"));
}

TEST(StagedFiles, AFolderCreationThatFailsPartWayLeavesNoLevelBehind) {
  const testing::TestFolder folder{"staged-files"};
  const fs::path& root = folder.path();
  const std::string too_long(300, 'x');  // longer than a file name may be (NAME_MAX 255)
  {
    StagedFiles staged;
    EXPECT_THROW(staged.make_folder((root / "made" / "deeper" / too_long).string()), fs::filesystem_error);
    EXPECT_TRUE(fs::is_directory(root / "made" / "deeper"));  // the levels before the one that failed
  }
  EXPECT_FALSE(fs::exists(root / "made"));
}

TEST(StagedFiles, FoldersMadeThroughASymlinkAndDotDotAreTheOnesRemoved) {
  // "link/.." is where the link points, one level up (the system resolves the link first), not `root`: the folder
  // made is real/new, and that is the one a failed set removes.
  const testing::TestFolder folder{"staged-files"};
  const fs::path& root = folder.path();
  fs::create_directories(root / "real" / "inner");
  fs::create_directory_symlink(root / "real" / "inner", root / "link");
  {
    StagedFiles staged;
    staged.make_folder((root / "link" / ".." / "new" / "maps").string());
    ASSERT_TRUE(fs::is_directory(root / "real" / "new" / "maps"));
    EXPECT_FALSE(fs::exists(root / "new"));
  }  // not published
  EXPECT_FALSE(fs::exists(root / "real" / "new"));
  EXPECT_TRUE(fs::is_directory(root / "real" / "inner"));  // there before: kept
}

TEST(StagedFiles, ALinkInTheWayIsNeverRemovedAndDotDotAfterAMissingLevelLeavesNoFolder) {
  const testing::TestFolder folder{"staged-files"};
  const fs::path& root = folder.path();
  fs::create_symlink(root / "nowhere", root / "dangling");  // the user's link, to nothing
  for (const fs::path& out : {root / "dangling", root / "dangling" / "sub"}) {
    {
      StagedFiles staged;
      EXPECT_THROW(staged.make_folder(out.string()), fs::filesystem_error);
    }
    EXPECT_TRUE(fs::is_symlink(fs::symlink_status(root / "dangling"))) << out;
  }
  // "m1/../x" is made as the system makes it (m1, then x beside it), so that files staged under that path can be
  // written; a failed set removes both.
  {
    StagedFiles staged;
    const fs::path out = root / "m1" / ".." / "x";
    staged.make_folder(out.string());
    EXPECT_TRUE(fs::is_directory(root / "x"));
    write_file(staged.stage((out / "a.png").string()), "a");
    EXPECT_EQ(std::distance(fs::directory_iterator(root / "x"), fs::directory_iterator{}), 1);
  }  // not published
  EXPECT_FALSE(fs::exists(root / "x"));
  EXPECT_FALSE(fs::exists(root / "m1"));
}

}  // namespace
}  // namespace texwarp
