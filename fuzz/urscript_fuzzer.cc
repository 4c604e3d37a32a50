// The UR controller emulator's URScript parser (tests/support/ur_emulator/
// urscript.h): whatever the text, a program of known calls or an error with
// a 1-based position.
#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_input.h"
#include "tests/support/ur_emulator/urscript.h"

namespace emu = cornerpose::ur_emulator;
using cornerpose::fuzz::Require;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const emu::ParseResult result = emu::ParseScript(cornerpose::fuzz::AsText(data, size));
  if (result.error) {
    Require(result.error->line >= 1 && result.error->column >= 1, "errors have a 1-based position");
    return 0;
  }
  for (const emu::ScriptCall& call : result.program.calls) {
    Require(emu::IsKnownFunction(call.function), "parsed calls name known built-ins");
    Require(call.line >= 1 && call.column >= 1, "calls have a 1-based position");
    for (const auto& [name, value] : call.args) (void)value.ToString();
  }
  return 0;
}
