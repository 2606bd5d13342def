# cmake -DSCOPEKIN=<exe> -DARGS=<a;b;c> -DEXPECTED_EXIT=<n> [-DPYTHON3=<py> -DJSON_CHECK=<script>] -P run_scopekin.cmake
#
# Runs the scopekin CLI and fails unless its exit status is exactly EXPECTED_EXIT. With
# JSON_CHECK, its standard output is also piped into `PYTHON3 JSON_CHECK`, which must exit 0.
# (A `sh -c "a | b"` pipeline would lose scopekin's own exit status.)
foreach(_var IN ITEMS SCOPEKIN ARGS EXPECTED_EXIT)
  if(NOT DEFINED ${_var})
    message(FATAL_ERROR "run_scopekin.cmake: -D${_var}=... is required")
  endif()
endforeach()

execute_process(
  COMMAND "${SCOPEKIN}" ${ARGS}
  OUTPUT_VARIABLE _stdout
  ERROR_VARIABLE _stderr
  RESULT_VARIABLE _exit)
string(REPLACE ";" " " _shown_args "${ARGS}")
if(NOT "${_exit}" STREQUAL "${EXPECTED_EXIT}")
  message(FATAL_ERROR "scopekin ${_shown_args}: exit status '${_exit}', expected ${EXPECTED_EXIT}\n"
                      "stdout:\n${_stdout}\nstderr:\n${_stderr}")
endif()

if(DEFINED JSON_CHECK)
  get_filename_component(_out_file "scopekin_stdout.json" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_BINARY_DIR}")
  file(WRITE "${_out_file}" "${_stdout}")
  execute_process(
    COMMAND "${PYTHON3}" "${JSON_CHECK}"
    INPUT_FILE "${_out_file}"
    OUTPUT_VARIABLE _check_out
    ERROR_VARIABLE _check_err
    RESULT_VARIABLE _check_exit)
  if(NOT "${_check_exit}" STREQUAL "0")
    message(FATAL_ERROR "scopekin ${_shown_args}: output failed ${JSON_CHECK} (exit '${_check_exit}')\n"
                        "${_check_out}${_check_err}\nstdout was:\n${_stdout}")
  endif()
endif()
message(STATUS "scopekin ${_shown_args}: exit status ${_exit} as expected")
