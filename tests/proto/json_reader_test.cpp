// Tests of parse_json and JsonReader: the nesting limit (exactly at and one past it, and a 32 MiB bomb refused at
// once), duplicate keys refused with their JSON path, unknown keys with the near known key suggested, UTF-8 cuts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <string>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/job_spec_codec.hpp"
#include "texwarp/proto/json_reader.hpp"
#include "texwarp/proto/utf8_text.hpp"
#include "texwarp/proto/warp_spec_codec.hpp"

namespace texwarp::proto {
namespace {

using ::testing::HasSubstr;

// The message of the InputError that parsing `text` throws ("(accepted)" when it parses).
std::string parse_error(const std::string& text) {
  try {
    parse_json(text, "t.json");
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

// `depth` openers of the form `open`, a scalar, then the matching closers.
std::string nested(std::size_t depth, const std::string& open, const std::string& close) {
  std::string text;
  for (std::size_t i = 0; i < depth; ++i) text += open;
  text += "1";
  for (std::size_t i = 0; i < depth; ++i) text += close;
  return text;
}

TEST(ParseJson, ArraysNestedExactlyToTheLimitParse) {
  const nlohmann::json j = parse_json(nested(kMaxJsonDepth, "[", "]"), "t.json");
  const nlohmann::json* v = &j;
  for (std::size_t i = 0; i < kMaxJsonDepth; ++i) {
    ASSERT_TRUE(v->is_array()) << "level " << i;
    ASSERT_EQ(v->size(), 1u);
    v = &(*v)[0];
  }
  EXPECT_EQ(*v, 1);
}

TEST(ParseJson, ArraysOneLevelPastTheLimitAreRefusedAtTheBracket) {
  EXPECT_EQ(kMaxJsonDepth, 64u);
  EXPECT_EQ(parse_error(nested(65, "[", "]")), "t.json: JSON nested deeper than 64 levels (byte 65)");
}

TEST(ParseJson, ObjectsNestedToTheLimitParseAndOnePastIsRefused) {
  EXPECT_EQ(parse_error(nested(64, R"({"a":)", "}")), "(accepted)");
  // The 65th "{" is byte 64 × 5 + 1 (1-based).
  EXPECT_EQ(parse_error(nested(65, R"({"a":)", "}")), "t.json: JSON nested deeper than 64 levels (byte 321)");
}

TEST(ParseJson, MixedNestingCountsArraysAndObjectsAlike) {
  // Each step opens an array and an object: `[{"k":` is 6 bytes, so the 65th opener ("[" of step 33) is byte 193.
  EXPECT_EQ(parse_error(nested(32, R"([{"k":)", "}]")), "(accepted)");
  EXPECT_EQ(parse_error(nested(32, R"([{"k":)", "}]") + " "), "(accepted)");
  EXPECT_EQ(parse_error(nested(33, R"([{"k":)", "}]")), "t.json: JSON nested deeper than 64 levels (byte 193)");
  // Width does not count: 64 deep, with siblings and whitespace before the offender.
  const std::string deep = std::string(63, '[') + "[1, [2]]" + std::string(63, ']');
  EXPECT_EQ(parse_error(deep), "t.json: JSON nested deeper than 64 levels (byte 68)");
  EXPECT_EQ(parse_error(std::string(63, '[') + "[1, 2], [3]" + std::string(63, ']')), "(accepted)");
}

TEST(ParseJson, A32MiBNestingBombIsRefusedAtOnce) {
  for (const std::string unit : {"[", R"({"a":)"}) {
    std::string bomb;
    bomb.reserve(32u << 20);
    while (bomb.size() + unit.size() <= (32u << 20)) bomb += unit;
    const auto start = std::chrono::steady_clock::now();
    const std::string message = parse_error(bomb);
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    EXPECT_THAT(message, HasSubstr("JSON nested deeper than 64 levels")) << unit;
    EXPECT_LT(seconds, 1.0) << unit;
  }
}

TEST(ParseJson, SyntaxErrorsStillNameTheSourceAndByte) {
  EXPECT_THAT(parse_error(R"({"a": )"), HasSubstr("t.json: not valid JSON (byte 7)"));
  EXPECT_THAT(parse_error("{} x"), HasSubstr("t.json: not valid JSON (byte 4)"));
  EXPECT_THAT(parse_error("[1e400]"), HasSubstr("t.json: not valid JSON"));
  EXPECT_THAT(parse_error(""), HasSubstr("t.json: not valid JSON (byte 1)"));
  EXPECT_THAT(parse_error("{\"a\": \"\xff\"}"), HasSubstr("t.json: not valid JSON"));
}

TEST(ParseJson, BuildsTheSameValueAsTheLibraryParser) {
  const std::string text = R"( {"name": "x\u00e9\ud83d\ude00", "n": [0, -1, 18446744073709551615, 1.5e-3, true, null],
    "o": {"a": {"b": [[], {}, [{}]]}, "c": ""}, "u": 9223372036854775807} )";
  const nlohmann::json expected = nlohmann::json::parse(text);
  const nlohmann::json got = parse_json(text, "t.json");
  EXPECT_EQ(got, expected);
  EXPECT_EQ(got.dump(), expected.dump());
  EXPECT_TRUE(got["n"][2].is_number_unsigned());
  EXPECT_EQ(parse_json("42", "t.json"), 42);
  EXPECT_EQ(parse_json("\"s\"", "t.json"), "s");
}

// Where and what of the DuplicateKeyError that parsing `text` throws.
std::string duplicate_at(const std::string& text) {
  try {
    parse_json(text, "request body");
  } catch (const DuplicateKeyError& e) {
    EXPECT_EQ(e.detail(), "duplicate key");
    EXPECT_EQ(e.where().file_name(), "request body");
    return e.where().without_file().str();
  } catch (const InputError& e) {
    return std::string("(other error) ") + e.what();
  }
  return "(accepted)";
}

TEST(ParseJson, DuplicateKeysAreRefusedWithTheirPath) {
  EXPECT_EQ(duplicate_at(R"({"a": 1, "b": 2, "a": 3})"), "$.a");
  EXPECT_EQ(duplicate_at(R"({"warp": {"features": [{"source": [0, 0], "target": [1, 1]}, {"source": [2, 2]},
    {"source": [0, 0], "target": [1, 1], "source": [5, 5]}]}})"),
            "$.warp.features[2].source");
  EXPECT_EQ(duplicate_at(R"([[0], [1, {"x": {"y": [], "y": {}}}]])"), "$[1][1].x.y");
  // The same key in sibling or nested objects is no repeat.
  EXPECT_EQ(duplicate_at(R"([{"a": 1}, {"a": 2}, {"a": {"a": {"a": 3}}}])"), "(accepted)");
  // Keys equal only after unescaping are the same key.
  EXPECT_EQ(duplicate_at(R"({"ab": 1, "a\u0062": 2})"), "$.ab");
  try {
    parse_json(R"({"k": 1, "k": 1})", "request body");
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().file_name(), "request body");
    EXPECT_EQ(e.message_without_file(), "$.k: duplicate key");
  }
}

// The message of the InputError that decoding a warp spec throws.
std::string warp_error(const std::string& text) {
  try {
    decode_warp_spec(parse_json(text, "t.json"), JsonPath{"warp"});
  } catch (const InputError& e) {
    return e.what();
  }
  return "(accepted)";
}

const std::string kFeatures = R"("features": [{"source": [1, 2], "target": [3, 4]}])";

TEST(JsonReader, AMissingRequiredKeyNamesANearUnknownKey) {
  EXPECT_EQ(warp_error(R"({"featurez": []})"),
            R"($.warp.features: required key is missing (there is an unknown key "featurez"))");
  EXPECT_EQ(warp_error(R"({"Features": []})"),
            R"($.warp.features: required key is missing (there is an unknown key "Features"))");
  EXPECT_EQ(warp_error(R"({"points": []})"), "$.warp.features: required key is missing");
}

TEST(JsonReader, AnUnknownKeySuggestsTheNearKnownKey) {
  EXPECT_EQ(warp_error("{" + kFeatures + R"(, "tolerance_pz": 1})"),
            R"($.warp.tolerance_pz: unknown key; did you mean "tolerance_px"?)");
  EXPECT_EQ(warp_error("{" + kFeatures + R"(, "ALPHA": 2})"), R"($.warp.ALPHA: unknown key; did you mean "alpha"?)");
  EXPECT_EQ(warp_error("{" + kFeatures + R"(, "aplha": 2})"), R"($.warp.aplha: unknown key; did you mean "alpha"?)");
  EXPECT_EQ(warp_error("{" + kFeatures + R"(, "prealing": "none"})"),
            R"($.warp.prealing: unknown key; did you mean "prealign"?)");
  // Nested objects, and a key of 4 characters or fewer allows one edit only.
  EXPECT_EQ(warp_error(R"({"features": [{"ix": "a", "source": [1, 2], "target": [3, 4]}]})"),
            R"($.warp.features[0].ix: unknown key; did you mean "id"?)");
  EXPECT_EQ(warp_error(R"({"features": [{"xy": "a", "source": [1, 2], "target": [3, 4]}]})"),
            "$.warp.features[0].xy: unknown key");
  // A far key gets no suggestion, nor does a near key whose known key is present too.
  EXPECT_EQ(warp_error("{" + kFeatures + R"(, "colour": 1})"), "$.warp.colour: unknown key");
  EXPECT_EQ(warp_error("{" + kFeatures + R"(, "alpha": 2, "alpha2": 2})"), "$.warp.alpha2: unknown key");
}

TEST(JsonReader, SuggestionsCoverKeysOfTheOtherVariantsOfAJob) {
  const std::string image = R"("image": {"blob": "sha256:)" + std::string(64, 'a') + R"("})";
  try {
    decode_job_spec(parse_json("{" + image + R"(, "wrap": {)" + kFeatures + "}}", "t.json"));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), R"($: expected exactly one of "warp", "mesh" (there is an unknown key "wrap"))");
  }
  try {
    decode_job_spec(parse_json("{" + image + R"(, "warp": {)" + kFeatures + R"(}, "option": {}})", "t.json"));
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), R"($.option: unknown key; did you mean "options"?)");
  }
}

TEST(JsonReader, UserKeysInMessagesAreCutBetweenCharacters) {
  std::string key = "a";
  for (int i = 0; i < 40; ++i) key += "\xC3\xA9";  // é: 81 bytes in all
  // 64 bytes would end inside the 32nd é: the cut keeps "a" and 31 of them.
  std::string kept = "a";
  for (int i = 0; i < 31; ++i) kept += "\xC3\xA9";
  const nlohmann::json doc = parse_json("{" + kFeatures + R"(, ")" + key + R"(": 1})", "t.json");
  try {
    decode_warp_spec(doc, JsonPath{"warp"});
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where().str(), "$.warp." + kept + "\xE2\x80\xA6");
    EXPECT_TRUE(is_valid_utf8(e.what()));
  }
  EXPECT_EQ(quoted_key(key), "\"" + kept + "\xE2\x80\xA6\"");
  EXPECT_EQ(quoted_key("a\"b\n"), R"("a\"b\n")");
  EXPECT_EQ(duplicate_at("{\"" + key + "\": 1, \"" + key + "\": 2}"), "$." + kept + "\xE2\x80\xA6");
}

}  // namespace
}  // namespace texwarp::proto
