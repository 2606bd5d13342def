# check_format.cmake — is the C and C++ source formatted as .clang-format says?
#
#   cmake -DSOURCE_DIR=<repository root> -DCLANG_FORMAT=<clang-format-14> -P cmake/check_format.cmake
#
# The CTest test `format` (label format) runs it.  Every .cpp/.hpp/.h/.c file under firmware/,
# hal/, model/, host_sim/ and tests/ is checked with `clang-format --dry-run --Werror`; a folder
# whose own .clang-format says `DisableFormat: true` (the generated reduced tables) is left as it
# is.  Fix a failure with:  clang-format-14 -i <file>...
# clang-format 14 (Debian 12's) is required: other versions format some constructs differently.
cmake_policy(VERSION 3.25)

if(NOT SOURCE_DIR OR NOT CLANG_FORMAT)
  message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=<root> -DCLANG_FORMAT=<clang-format> -P check_format.cmake")
endif()

set(files "")
foreach(tree firmware hal model host_sim tests)
  file(GLOB_RECURSE found RELATIVE "${SOURCE_DIR}"
       "${SOURCE_DIR}/${tree}/*.cpp" "${SOURCE_DIR}/${tree}/*.hpp"
       "${SOURCE_DIR}/${tree}/*.h" "${SOURCE_DIR}/${tree}/*.c")
  list(APPEND files ${found})
endforeach()
# Packages a hand-run `npm install` puts beside the view's page are not ours.
list(FILTER files EXCLUDE REGEX "/node_modules/")
list(SORT files)

# Batches keep each command line short.
set(unformatted "")
set(batch "")
list(LENGTH files total)
set(index 0)
foreach(file IN LISTS files)
  list(APPEND batch "${file}")
  math(EXPR index "${index} + 1")
  list(LENGTH batch size)
  if(size EQUAL 40 OR index EQUAL total)
    execute_process(COMMAND "${CLANG_FORMAT}" --dry-run --Werror ${batch}
                    WORKING_DIRECTORY "${SOURCE_DIR}"
                    RESULT_VARIABLE status ERROR_VARIABLE report OUTPUT_QUIET)
    if(NOT status EQUAL 0)
      string(REGEX MATCHALL "[^\n]+: error: code should be clang-formatted" lines "${report}")
      foreach(line IN LISTS lines)
        string(REGEX REPLACE ":[0-9]+:[0-9]+: error: code should be clang-formatted" "" name "${line}")
        list(APPEND unformatted "${name}")
      endforeach()
      if(NOT lines)
        message(FATAL_ERROR "format: ${CLANG_FORMAT} failed:\n${report}")
      endif()
    endif()
    set(batch "")
  endif()
endforeach()

if(unformatted)
  list(REMOVE_DUPLICATES unformatted)
  list(LENGTH unformatted count)
  list(JOIN unformatted "\n  " text)
  message(FATAL_ERROR "format: ${count} of ${total} files differ from .clang-format "
                      "(fix: clang-format-14 -i <file>):\n  ${text}")
endif()
message(STATUS "format: ${total} files as .clang-format says")
