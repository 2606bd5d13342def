# The DBC check (included by tests/hal/can/CMakeLists.txt): every typed encoder and decoder of
# firmware/protocol/can/scopekin_messages.hpp against firmware/protocol/scopekin.dbc as read by
# python3-canmatrix (Debian package).
#
#   scopekin_protocol_codec_tool      the codecs behind a JSON-lines interface (protocol_codec_tool.cpp)
#   can_protocol.dbc_matches_codecs   check_dbc.py <tool> <dbc>   (label: can)
#
# Host presets only (host, asan): the tool runs natively and the check needs Debian's Python.
# canmatrix is REQUIRED there: a missing package fails the configure (never a silently skipped
# test).  Debian's interpreter is /usr/bin/python3; a `python3` earlier on PATH (pyenv, venv) does
# not see Debian's python3-* packages, so /usr/bin is searched first.
if(CMAKE_CROSSCOMPILING)
  return()
endif()

find_package(nlohmann_json 3 REQUIRED CONFIG)

add_executable(scopekin_protocol_codec_tool ${CMAKE_CURRENT_LIST_DIR}/protocol_codec_tool.cpp)
target_link_libraries(scopekin_protocol_codec_tool PRIVATE
  scopekin::can_protocol nlohmann_json::nlohmann_json)
scopekin_strict_warnings(scopekin_protocol_codec_tool)

find_program(SCOPEKIN_CANMATRIX_PYTHON3 NAMES python3 PATHS /usr/bin NO_DEFAULT_PATH
  DOC "Python 3 with canmatrix (Debian: python3-canmatrix), for the DBC check")
if(NOT SCOPEKIN_CANMATRIX_PYTHON3)
  find_program(SCOPEKIN_CANMATRIX_PYTHON3 NAMES python3
    DOC "Python 3 with canmatrix (Debian: python3-canmatrix), for the DBC check")
endif()
if(NOT SCOPEKIN_CANMATRIX_PYTHON3)
  message(FATAL_ERROR "The DBC check (can_protocol.dbc_matches_codecs) needs Python 3 with "
    "canmatrix: install the Debian packages python3 and python3-canmatrix "
    "(./scopekin.sh installs them).")
endif()
execute_process(
  COMMAND ${SCOPEKIN_CANMATRIX_PYTHON3} -c "import canmatrix.formats"
  RESULT_VARIABLE _scopekin_canmatrix_rc
  OUTPUT_QUIET ERROR_VARIABLE _scopekin_canmatrix_err)
if(NOT _scopekin_canmatrix_rc EQUAL 0)
  message(FATAL_ERROR "The DBC check (can_protocol.dbc_matches_codecs) needs canmatrix, which "
    "${SCOPEKIN_CANMATRIX_PYTHON3} cannot import: install the Debian package python3-canmatrix "
    "(apt-get install python3-canmatrix; ./scopekin.sh installs it), or set "
    "SCOPEKIN_CANMATRIX_PYTHON3 to a Python 3 that has canmatrix.\n${_scopekin_canmatrix_err}")
endif()

add_test(NAME can_protocol.dbc_matches_codecs
  COMMAND ${SCOPEKIN_CANMATRIX_PYTHON3} ${CMAKE_CURRENT_LIST_DIR}/check_dbc.py
          $<TARGET_FILE:scopekin_protocol_codec_tool>
          ${PROJECT_SOURCE_DIR}/firmware/protocol/scopekin.dbc)
set_tests_properties(can_protocol.dbc_matches_codecs PROPERTIES LABELS can TIMEOUT 300)
