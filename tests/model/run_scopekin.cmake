# cmake -DSCOPEKIN=<exe> -DARGS=<a;b;c> -DEXPECTED_EXIT=<n> [-DPYTHON3=<py> -DJSON_CHECK=<script>]
#       [-DOUT_DIR=<dir> [-DEXPECT_FILES=<f;g>] [-DEXPECT_NO_FILES=<f;g>] [-DEXPECT_STATUS=<s>]
#        [-DEXPECT_NO_OUT_DIR=ON]] -P run_scopekin.cmake
#
# Runs the scopekin CLI and fails unless its exit status is exactly EXPECTED_EXIT. With
# JSON_CHECK, its standard output is also piped into `PYTHON3 JSON_CHECK`, which must exit 0.
# (A `sh -c "a | b"` pipeline would lose scopekin's own exit status.)
# With OUT_DIR (an output directory the command writes, e.g. `simulate --out`): OUT_DIR is
# removed before the run; afterwards the files EXPECT_FILES (names in OUT_DIR) must exist, the
# files EXPECT_NO_FILES must not, OUT_DIR/summary.json must have "status" EXPECT_STATUS, and with
# EXPECT_NO_OUT_DIR the directory must not exist at all (nothing written).
foreach(_var IN ITEMS SCOPEKIN ARGS EXPECTED_EXIT)
  if(NOT DEFINED ${_var})
    message(FATAL_ERROR "run_scopekin.cmake: -D${_var}=... is required")
  endif()
endforeach()

if(DEFINED OUT_DIR)
  file(REMOVE_RECURSE "${OUT_DIR}")
endif()

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
if(DEFINED OUT_DIR)
  set(_context "scopekin ${_shown_args}\nstdout:\n${_stdout}\nstderr:\n${_stderr}")
  if(EXPECT_NO_OUT_DIR AND EXISTS "${OUT_DIR}")
    file(GLOB _written "${OUT_DIR}/*")
    message(FATAL_ERROR "${_context}\nexpected nothing written, but ${OUT_DIR} exists (${_written})")
  endif()
  foreach(_file IN LISTS EXPECT_FILES)
    if(NOT EXISTS "${OUT_DIR}/${_file}")
      message(FATAL_ERROR "${_context}\nexpected ${OUT_DIR}/${_file} to exist")
    endif()
  endforeach()
  foreach(_file IN LISTS EXPECT_NO_FILES)
    if(EXISTS "${OUT_DIR}/${_file}")
      message(FATAL_ERROR "${_context}\nexpected no ${OUT_DIR}/${_file}")
    endif()
  endforeach()
  if(DEFINED EXPECT_STATUS)
    file(READ "${OUT_DIR}/summary.json" _summary)
    string(JSON _status ERROR_VARIABLE _json_error GET "${_summary}" status)
    if(NOT "${_status}" STREQUAL "${EXPECT_STATUS}")
      message(FATAL_ERROR "${_context}\n${OUT_DIR}/summary.json: status '${_status}' ${_json_error}, expected '${EXPECT_STATUS}'")
    endif()
  endif()
endif()
message(STATUS "scopekin ${_shown_args}: exit status ${_exit} as expected")
