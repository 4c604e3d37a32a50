// The UR emulator's URScript subset parser: the daemon's job program
// outline compiles, and bad scripts are rejected with the line and column
// the controller would report.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tests/support/ur_emulator/urscript.h"

namespace cornerpose::ur_emulator {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;

// ur-interface.md section 3, with literals filled in.
constexpr char kJobProgram[] = R"(def job_42():
  # approach, grasp, retrieve, place
  socket_open("10.0.0.5", 50010, "rep")
  set_tcp(p[0,0,0.12,0,0,0])
  movej(p[0.4, -0.2, 0.3, 3.14159, 0, 0], a=1.0, v=0.8)
  movel(p[0.4, -0.2, 0.15, 3.14159, 0, 0], a=0.5, v=0.05)
  set_tool_digital_out(0, True)
  sleep(0.3)

  movel(p[0.4, -0.2, 0.45, 3.14159, 0, 0], a=0.5, v=0.1)  # retrieve
  movej(p[-0.3, -0.4, 0.3, 3.14159, 0, 0], a=1.0, v=0.8)
  set_tool_digital_out(0, False)
  socket_send_line("job_42 done", "rep")
end
)";

TEST(UrScriptParser, AcceptsTheJobProgramOutline) {
  const ParseResult result = ParseScript(kJobProgram);
  ASSERT_FALSE(result.error) << result.error->text;
  EXPECT_EQ(result.program.name, "job_42");
  std::vector<std::string> functions;
  for (const ScriptCall& call : result.program.calls) functions.push_back(call.function);
  EXPECT_THAT(functions,
              ElementsAre("socket_open", "set_tcp", "movej", "movel", "set_tool_digital_out",
                          "sleep", "movel", "movej", "set_tool_digital_out", "socket_send_line"));
  const ScriptCall& movej = result.program.calls[2];
  EXPECT_EQ(movej.line, 5);
  EXPECT_EQ(movej.column, 3);
  EXPECT_EQ(movej.arg("q").kind, ScriptValue::Kind::kPose);
  EXPECT_THAT(movej.arg("q").elements, ElementsAre(0.4, -0.2, 0.3, 3.14159, 0, 0));
  EXPECT_DOUBLE_EQ(movej.arg("a").number, 1.0);
  EXPECT_DOUBLE_EQ(movej.arg("v").number, 0.8);
  EXPECT_DOUBLE_EQ(movej.arg("t").number, 0.0);  // default filled in
  EXPECT_TRUE(result.program.calls[4].arg("b").boolean);
  EXPECT_FALSE(result.program.calls[8].arg("b").boolean);
  EXPECT_EQ(result.program.calls[9].arg("socket_name").text, "rep");
}

TEST(UrScriptParser, LiteralsAndKeywordArguments) {
  const ParseResult result = ParseScript(
      "def lits():\n"
      "  movej([0, -1.5e0, 1.57, -1.2E-1, -.5, +2], t=2.5, r=0)\n"
      "  textmsg(\"a # not a comment\", 3)\n"
      "  set_payload(1.5, [0, 0, 0.05])\n"
      "  set_payload(m=2)\n"
      "  movel(pose=[0,0,0,0,0,0])\n"
      "end\n");
  ASSERT_FALSE(result.error) << result.error->text;
  ASSERT_EQ(result.program.calls.size(), 5u);
  EXPECT_THAT(result.program.calls[0].arg("q").elements,
              ElementsAre(0, -1.5, 1.57, -0.12, -0.5, 2));
  EXPECT_DOUBLE_EQ(result.program.calls[0].arg("t").number, 2.5);
  EXPECT_EQ(result.program.calls[1].arg("s1").text, "a # not a comment");
  EXPECT_EQ(result.program.calls[1].arg("s2").ToString(), "3");
  EXPECT_FALSE(result.program.calls[3].has("cog"));
  EXPECT_DOUBLE_EQ(result.program.calls[4].arg("a").number, 1.2);
}

TEST(UrScriptParser, BareStatementsAreAnUnnamedProgram) {
  const ParseResult result = ParseScript("set_standard_digital_out(3, True)\n");
  ASSERT_FALSE(result.error) << result.error->text;
  EXPECT_EQ(result.program.name, "unnamed");
  ASSERT_EQ(result.program.calls.size(), 1u);
}

TEST(UrScriptParser, LongNamesAreTruncatedTo31Characters) {
  const ParseResult result =
      ParseScript("def abcdefghijklmnopqrstuvwxyz0123456789():\n  sync()\nend\n");
  ASSERT_FALSE(result.error) << result.error->text;
  EXPECT_EQ(result.program.name, "abcdefghijklmnopqrstuvwxyz01234");
}

struct BadCase {
  const char* script;
  int line;
  int column;
  const char* text;
};

TEST(UrScriptParser, RejectsBadScriptsWithLineAndColumn) {
  const BadCase cases[] = {
      // The controller's own example: unknown function on line 2, column 3.
      {"def test_fun():\n  calldoesntexist()\nend\n", 2, 3,
       "compile_error_name_not_found:calldoesntexist:"},
      {"def f():\n  movej([0,0,0,0,0,0]\nend\n", 2, 22, "syntax_error_on_line:2:"},
      {"def f():\nmovej([0,0,0,0,0,0])\nend\n", 2, 1, "syntax_error_on_line:2:"},
      {"def f():\n  sync()\n", 2, 1, "syntax_error_on_line:2:end of file"},
      {"def f():\n  sync()\n  end\n", 3, 3, "syntax_error_on_line:3:"},
      {"def f():\n  sync()\nend\n  sync()\n", 4, 1, "syntax_error_on_line:4:"},
      {"def 9f():\n  sync()\nend\n", 1, 5, "syntax_error_on_line:1:"},
      {"def f():\n  x = 1\nend\n", 2, 5, "syntax_error_on_line:2:"},
      {"def f():\n  movel(p[1,2,3])\nend\n", 2, 9, "syntax_error_on_line:2:"},
      {"def f():\n  movej(q)\nend\n", 2, 9, "compile_error_name_not_found:q:"},
      {"def f():\n  set_tool_digital_out(0, 1)\nend\n", 2, 3,
       "compile_error_type_mismatch:set_tool_digital_out:b:"},
      {"def f():\n  set_tool_digital_out(2, True)\nend\n", 2, 3,
       "runtime_error_index_out_of_range:set_tool_digital_out:"},
      {"def f():\n  movej([0,0,0,0,0,0], b=1)\nend\n", 2, 3,
       "compile_error_argument_mismatch:movej:"},
      {"def f():\n  movej([0,0,0,0,0,0], a=1, 2)\nend\n", 2, 29, "syntax_error_on_line:2:"},
      {"def f():\n  sleep()\nend\n", 2, 3, "compile_error_argument_mismatch:sleep:"},
      {"def f():\n  textmsg(\"open)\nend\n", 2, 11, "syntax_error_on_line:2:"},
      {"def f():\n  movej([0,0,0,0,0,0], a=-1)\nend\n", 2, 3,
       "runtime_error_negative_argument:movej:a:"},
      {"  def f():\n  sync()\nend\n", 1, 3, "syntax_error_on_line:1:"},
      {"", 1, 1, "syntax_error_on_line:1:"},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.script);
    const ParseResult result = ParseScript(c.script);
    ASSERT_TRUE(result.error);
    EXPECT_EQ(result.error->line, c.line);
    EXPECT_EQ(result.error->column, c.column);
    EXPECT_THAT(result.error->text, HasSubstr(c.text));
    EXPECT_TRUE(result.program.calls.empty());
  }
}

TEST(UrScriptParser, KnowsTheSubsetsFunctions) {
  EXPECT_TRUE(IsKnownFunction("movel"));
  EXPECT_TRUE(IsKnownFunction("protective_stop"));
  EXPECT_FALSE(IsKnownFunction("servoj"));
}

}  // namespace
}  // namespace cornerpose::ur_emulator
