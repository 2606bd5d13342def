# cmake -DBOX=<scopekin-box> [-DEMULATOR=<qemu-aarch64;-L;...>] -DARGS=<a;b> -DEXPECTED_EXIT=<n>
#       [-DEXPECT_OUTPUT=<regex>] -P run_box_cli.cmake
# Runs scopekin-box (through the cross emulator if any) and fails unless the exit status is
# EXPECTED_EXIT and stdout+stderr match EXPECT_OUTPUT.
foreach(_var IN ITEMS BOX EXPECTED_EXIT)
  if(NOT DEFINED ${_var})
    message(FATAL_ERROR "run_box_cli.cmake: -D${_var}=... is required")
  endif()
endforeach()
execute_process(COMMAND ${EMULATOR} "${BOX}" ${ARGS}
  OUTPUT_VARIABLE _stdout ERROR_VARIABLE _stderr RESULT_VARIABLE _exit)
string(REPLACE ";" " " _shown "${ARGS}")
if(NOT "${_exit}" STREQUAL "${EXPECTED_EXIT}")
  message(FATAL_ERROR "scopekin-box ${_shown}: exit status '${_exit}', expected ${EXPECTED_EXIT}\n"
                      "stdout:\n${_stdout}\nstderr:\n${_stderr}")
endif()
if(DEFINED EXPECT_OUTPUT AND NOT "${_stdout}${_stderr}" MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "scopekin-box ${_shown}: output does not match '${EXPECT_OUTPUT}'\n"
                      "stdout:\n${_stdout}\nstderr:\n${_stderr}")
endif()
message(STATUS "scopekin-box ${_shown}: exit ${_exit} as expected")
