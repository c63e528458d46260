// Tests of the typed error locations: JSON paths built by appends and rebased into their document, locations with
// and without their file, and the messages InputError composes from them.
#include <gtest/gtest.h>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/input_location.hpp"
#include "texwarp/proto/json_path.hpp"

namespace texwarp::proto {
namespace {

TEST(JsonPath, AppendsKeysAndIndices) {
  EXPECT_EQ(JsonPath().str(), "$");
  EXPECT_TRUE(JsonPath().is_root());
  EXPECT_EQ(JsonPath().key("warp").key("features").index(3).key("source").str(), "$.warp.features[3].source");
  EXPECT_EQ((JsonPath{"options", "device"}).str(), "$.options.device");
  EXPECT_EQ(JsonPath().index(0).index(12).str(), "$[0][12]");
  EXPECT_EQ(JsonPath{"a"}.key("b"), (JsonPath{"a", "b"}));
  EXPECT_NE(JsonPath{"a"}.index(0), JsonPath{"a"}.key("0"));
}

TEST(JsonPath, RebasedPlacesASubDocumentsPathUnderItsBase) {
  const JsonPath in_features = JsonPath{"features"}.index(2).key("target").key("face");
  EXPECT_EQ(in_features.rebased(JsonPath{"mesh", "features"}).str(), "$.mesh.features.features[2].target.face");
  EXPECT_EQ(JsonPath().rebased(JsonPath{"image"}).str(), "$.image");
  EXPECT_EQ(in_features.rebased(JsonPath()), in_features);
}

TEST(InputLocation, StrNamesTheFileThenThePlace) {
  EXPECT_EQ(InputLocation().str(), "");
  EXPECT_TRUE(InputLocation().empty());
  EXPECT_EQ(InputLocation(JsonPath{"alpha"}).str(), "$.alpha");
  EXPECT_EQ(InputLocation::flag("--device").str(), "--device");
  EXPECT_EQ(InputLocation::file("f.json").str(), "f.json");
  EXPECT_EQ(InputLocation(JsonPath{"features"}.index(1)).in_file("f.json").str(), "f.json: $.features[1]");
}

TEST(InputLocation, InFileKeepsAFileAlreadyNamed) {
  const InputLocation parsed = InputLocation::file("inner.json");
  EXPECT_EQ(parsed.in_file("outer.json").file_name(), "inner.json");
  EXPECT_EQ(InputLocation().in_file("outer.json").str(), "outer.json");
}

TEST(InputLocation, RebasedDropsTheFileAndKeepsThePathUnderTheBase) {
  // An image the server read from its own disk: the job names it at $.image; the server's path is gone.
  const InputLocation server_file = InputLocation::file("/srv/texwarpd/blobs/ab/cd");
  EXPECT_EQ(server_file.rebased(JsonPath{"image"}), InputLocation(JsonPath{"image"}));
  // A place inside a sub-document (a mesh file's JSON) goes under the sub-document's place in the job.
  const InputLocation in_mesh = InputLocation(JsonPath{"vertices"}.index(4)).in_file("mesh.json");
  const InputLocation placed = in_mesh.rebased(JsonPath{"mesh", "source"});
  EXPECT_EQ(placed.str(), "$.mesh.source.vertices[4]");
  EXPECT_TRUE(placed.file_name().empty());
  EXPECT_EQ(InputLocation().rebased(JsonPath{"warp"}).str(), "$.warp");
}

TEST(InputError, MessagesWithAndWithoutTheFile) {
  const InputError e(InputLocation(JsonPath{"features"}.index(0).key("source")).in_file("f.json"), "expected a point");
  EXPECT_STREQ(e.what(), "f.json: $.features[0].source: expected a point");
  EXPECT_EQ(e.message_without_file(), "$.features[0].source: expected a point");
  EXPECT_EQ(e.detail(), "expected a point");
  EXPECT_EQ(e.where().json_path()->str(), "$.features[0].source");
  const InputError whole({}, "the job is empty");
  EXPECT_STREQ(whole.what(), "the job is empty");
  const InputError file_only(InputLocation::file("/srv/x.png"), "no such file");
  EXPECT_STREQ(file_only.what(), "/srv/x.png: no such file");
  EXPECT_EQ(file_only.message_without_file(), "no such file");
}

}  // namespace
}  // namespace texwarp::proto
