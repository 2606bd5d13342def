# check_layering.cmake — the direction of the layers, checked on the sources:
#
#   hal/ (interfaces, backends)  <-  firmware/ (drivers, estimator, executive)  <-  model/, host_sim/
#
# A file under firmware/ or hal/ must not include anything of model/ or host_sim/, and a file under
# hal/ must not include firmware/ (its top-level folders: kinetics/, protocol/, drivers/, ...).
# The include paths already keep them apart (firmware/ and hal/ export only their own trees);
# this check also catches relative includes ("../../model/x.hpp") and says which line is wrong.
#
# Two uses:
#   include(check_layering) + scopekin_check_layering(<source dir>)   at configure time (fatal)
#   cmake -DSOURCE_DIR=<dir> -P cmake/check_layering.cmake             as the CTest test `layering`
include_guard(GLOBAL)
cmake_policy(VERSION 3.25)  # IN_LIST, also in script mode

# The first path component of an include, and every component, of `path` ("a/b/c.hpp").
function(_scopekin_include_components path out_first out_all)
  string(REPLACE "\\" "/" path "${path}")
  string(REPLACE "/" ";" parts "${path}")
  list(FILTER parts EXCLUDE REGEX "^\\.?$")
  set(first "")
  foreach(part IN LISTS parts)
    if(NOT part STREQUAL "..")
      set(first "${part}")
      break()
    endif()
  endforeach()
  set(${out_first} "${first}" PARENT_SCOPE)
  set(${out_all} "${parts}" PARENT_SCOPE)
endfunction()

# Appends "file:line: message" to `out_violations` for each include of `file` that breaks a rule.
#   forbidden_any    components no include may contain (model, host_sim)
#   forbidden_first  first components no include may start with (firmware's folders, for hal/)
function(_scopekin_check_file file relative forbidden_any forbidden_first out_violations)
  set(violations "${${out_violations}}")
  file(STRINGS "${file}" lines)
  set(number 0)
  foreach(line IN LISTS lines)
    math(EXPR number "${number} + 1")
    if(NOT line MATCHES "^[ \t]*#[ \t]*include[ \t]*[\"<]([^\">]+)[\">]")
      continue()
    endif()
    set(included "${CMAKE_MATCH_1}")
    _scopekin_include_components("${included}" first all)
    set(bad "")
    foreach(part IN LISTS all)
      if(part IN_LIST forbidden_any)
        set(bad "includes ${part}/ (${included})")
      endif()
    endforeach()
    if(NOT bad AND first IN_LIST forbidden_first)
      set(bad "hal/ includes firmware's ${first}/ (${included})")
    endif()
    if(bad)
      list(APPEND violations "${relative}:${number}: ${bad}")
    endif()
  endforeach()
  set(${out_violations} "${violations}" PARENT_SCOPE)
endfunction()

# Returns the violations of the layering in `source_dir` (empty list: none).
function(scopekin_layering_violations source_dir out_violations)
  set(forbidden_any model host_sim)
  # firmware's top-level folders (and "firmware" itself) are off limits for hal/.
  file(GLOB firmware_entries LIST_DIRECTORIES true RELATIVE "${source_dir}/firmware"
       "${source_dir}/firmware/*")
  set(firmware_folders firmware)
  foreach(entry IN LISTS firmware_entries)
    if(IS_DIRECTORY "${source_dir}/firmware/${entry}")
      list(APPEND firmware_folders "${entry}")
    endif()
  endforeach()
  set(violations "")
  foreach(tree firmware hal)
    file(GLOB_RECURSE files RELATIVE "${source_dir}"
         "${source_dir}/${tree}/*.hpp" "${source_dir}/${tree}/*.cpp" "${source_dir}/${tree}/*.h"
         "${source_dir}/${tree}/*.c" "${source_dir}/${tree}/*.inc" "${source_dir}/${tree}/*.S")
    list(SORT files)
    set(first_rule "")
    if(tree STREQUAL "hal")
      set(first_rule "${firmware_folders}")
    endif()
    foreach(relative IN LISTS files)
      _scopekin_check_file("${source_dir}/${relative}" "${relative}" "${forbidden_any}"
                           "${first_rule}" violations)
    endforeach()
  endforeach()
  set(${out_violations} "${violations}" PARENT_SCOPE)
endfunction()

function(scopekin_check_layering source_dir)
  scopekin_layering_violations("${source_dir}" violations)
  if(violations)
    list(JOIN violations "\n  " text)
    message(FATAL_ERROR "layering: firmware/ and hal/ may not include model/ or host_sim/, and "
                        "hal/ may not include firmware/:\n  ${text}")
  endif()
endfunction()

# Script mode (the CTest test).
if(CMAKE_SCRIPT_MODE_FILE AND CMAKE_SCRIPT_MODE_FILE STREQUAL CMAKE_CURRENT_LIST_FILE)
  if(NOT SOURCE_DIR)
    message(FATAL_ERROR "usage: cmake -DSOURCE_DIR=<repository root> -P check_layering.cmake")
  endif()
  scopekin_check_layering("${SOURCE_DIR}")
  message(STATUS "layering: firmware/ and hal/ include nothing of model/ or host_sim/; "
                 "hal/ includes nothing of firmware/")
endif()
