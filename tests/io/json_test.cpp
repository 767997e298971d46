#include "trueaxis/io/json.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <limits>

#include "trueaxis/error.hpp"

using trueaxis::Error;
using trueaxis::io::JsonFile;
using P = JsonFile::pointer;

TEST(JsonFile, LocatesValuesAfterNestedContainers) {
  // Index counting must survive nested arrays/objects before the target.
  const auto j = JsonFile::parse(
      "{\"lines\": [\n  {\"h\": [1, [2, 3], {\"a\": 4}], \"n\": \"a\"},\n  {\"h\": [5, true, "
      "null, -6.5e1]}\n]}",
      "l.json");
  EXPECT_EQ(j.where(P("/lines/0/h/2/a")), "l.json:2:27: ");
  EXPECT_EQ(j.where(P("/lines/0/n")), "l.json:2:37: ");
  EXPECT_EQ(j.where(P("/lines/1/h/3")), "l.json:3:25: ");
  EXPECT_EQ(j.where(P("/lines/1")), "l.json:3:3: ");
  // A missing value is located at its deepest existing parent.
  EXPECT_EQ(j.where(P("/lines/1/spacing")), "l.json:3:3: ");
  EXPECT_EQ(j.number(P("/lines/1/h/3")), -65);
}

TEST(JsonFile, TypedAccessErrorsNameThePathAndPosition) {
  const auto j = JsonFile::parse("{\"a\": {\"b\": \"x\", \"c\": [1, 2]}}", "t.json");
  auto err = [&](auto fn) {
    try {
      fn();
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(err([&] { j.number(P("/a/b")); }), "t.json:1:13: 'a.b' must be a number");
  EXPECT_EQ(err([&] { j.string(P("/a/c/1")); }), "t.json:1:27: 'a.c[1]' must be a string");
  EXPECT_EQ(err([&] { j.array(P("/a/d")); }), "t.json:1:7: 'a.d' is missing");
  EXPECT_EQ(err([&] { j.object(P("/a/c")); }), "t.json:1:23: 'a.c' must be an object");
  EXPECT_EQ(err([] {
              JsonFile::parse("{\n\"a\": [1,, 2]}", "s.json");
            }).rfind("s.json:2:9: invalid JSON", 0),
            0u);
  EXPECT_THROW(JsonFile::read("/nonexistent.json"), Error);
  // The parser's own wording is put into words: what was found, what was expected.
  const std::pair<const char*, const char*> cases[] = {
      {"ISO-10303-21;", "b.json:1:1: invalid JSON: 'I': not a JSON value"},
      {"{\"a\": tru}", "b.json:1:10: invalid JSON: 'tru': not a JSON value"},
      {"{\"a\": 1", "b.json:1:8: invalid JSON: the text ends before the JSON does"},
      {"{\"a\": 1 \"b\": 2}",
       "b.json:1:11: invalid JSON: unexpected text in double quotes (a ',' "
       "missing before it?)"},
      {"{\"a\": 1,}", "b.json:1:9: invalid JSON: unexpected '}'; expected a key in double quotes"},
  };
  for (const auto& c : cases) {
    const char* text = c.first;  // a lambda cannot capture a structured binding (clang 14)
    const char* expect = c.second;
    const std::string m = err([&] { JsonFile::parse(text, "b.json"); });
    EXPECT_EQ(m.rfind(expect, 0), 0u) << m;
    EXPECT_EQ(m.find("json.exception"), std::string::npos) << m;
    EXPECT_EQ(m.find("last read"), std::string::npos) << m;
  }
}

// A repeated key is refused where it repeats (nlohmann kept the last copy silently, and a
// message about its value pointed at the first copy).
TEST(JsonFile, ADuplicatedKeyIsRefusedAtTheDuplicate) {
  auto err = [](const std::string& text) {
    try {
      trueaxis::io::JsonFile::parse(text, "d.json");
    } catch (const trueaxis::Error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(err("{\"spacing\": 50,\n \"seed\": 1, \"spacing\": 60}"),
            "d.json:2:13: duplicated key 'spacing'");
  EXPECT_EQ(err(R"({"a": {"b": 1, "c": {"b": 2}}, "d": [{"x": 1}, {"x": 2, "x": 3}]})"),
            "d.json:1:57: duplicated key 'x'");
  EXPECT_EQ(err(R"({"a": {"b": 1}, "b": {"a": 2}})"), "(no error)");  // other objects: fine
}

// Found by fuzzing: results with non-finite numbers were written as null (or bare inf/nan
// tokens) with exit code 0. A result file never holds one: the write is refused.
TEST(JsonFile, ANonFiniteResultIsNeverWritten) {
  nlohmann::ordered_json j;
  j["fine"] = 1.5;
  j["values"] = {1.0, std::numeric_limits<double>::infinity()};
  const std::string p = std::string(TRUEAXIS_TEST_TMP) + "/nonfinite.json";
  std::remove(p.c_str());
  try {
    trueaxis::io::write_json(p, j);
    ADD_FAILURE() << "written";
  } catch (const trueaxis::Error& e) {
    EXPECT_NE(std::string(e.what()).find("the computed value at /values/1 is not finite"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(p));
}
