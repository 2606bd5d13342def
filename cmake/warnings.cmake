# scopekin_strict_warnings(<target>)
#
# The project's warning set, as errors.  Applies to the target's own sources only (PRIVATE);
# third-party headers (Eigen, GoogleTest) arrive through SYSTEM include directories and are exempt.
include_guard(GLOBAL)

function(scopekin_strict_warnings target)
  target_compile_options(${target} PRIVATE
    -Wall
    -Wextra
    -Wpedantic
    -Wshadow
    -Wconversion
    -Wsign-conversion
    $<$<COMPILE_LANGUAGE:CXX>:-Wold-style-cast>
    -Werror)
endfunction()
