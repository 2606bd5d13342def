# scopekin_firmware_target(<target>)
#
# Everything compiled as firmware (firmware/, the hal/ parts it links, the bare-metal platform
# code and the bare-metal test runner) gets:
#   * the strict warning set (scopekin_strict_warnings),
#   * -fno-exceptions -fno-rtti   (hard rule: no exceptions, no RTTI),
#   * EIGEN_NO_MALLOC             (any Eigen heap allocation is an assertion failure).
#
# EIGEN_NO_MALLOC is PRIVATE on purpose: firmware public headers do not expose Eigen, and the
# firmware only uses fixed-size Eigen objects, which never instantiate Eigen's allocation
# functions — so host code that links the firmware library and uses dynamic Eigen (model/)
# does not see a second, different definition of those inline functions.
include_guard(GLOBAL)
include(warnings)

function(scopekin_firmware_target target)
  scopekin_strict_warnings(${target})
  target_compile_options(${target} PRIVATE
    $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions>
    $<$<COMPILE_LANGUAGE:CXX>:-fno-rtti>)
  target_compile_definitions(${target} PRIVATE EIGEN_NO_MALLOC)
endfunction()
