# Warnings for the project's own targets (not for third-party headers, which
# are included as SYSTEM).
function(cornerpose_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
endfunction()
