# scopekin_firmware_target(<target>)
#
# Everything compiled as firmware (firmware/, the hal/ parts it links, the bare-metal platform
# code and the bare-metal test runner) gets:
#   * the strict warning set (scopekin_strict_warnings),
#   * -fno-exceptions -fno-rtti   (hard rule: no exceptions, no RTTI).
# The firmware uses no Eigen (it links none; only model/ and host_sim/ do).
include_guard(GLOBAL)
include(warnings)

function(scopekin_firmware_target target)
  scopekin_strict_warnings(${target})
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions>
    $<$<COMPILE_LANGUAGE:CXX>:-fno-rtti>)
endfunction()
