# GoogleTest for hosted targets.
#   native build     -> Debian's packaged GTest (find_package, CONFIG from libgtest-dev)
#   cross, hosted OS -> build GoogleTest from the Debian source package (/usr/src/googletest)
#                       with the cross compiler; tests run under CMAKE_CROSSCOMPILING_EMULATOR
#   bare metal       -> no GoogleTest; tests use tests/firmware/portable_check.hpp's own runner
# Either way the targets are called GTest::gtest and GTest::gtest_main.
include_guard(GLOBAL)

set(SCOPEKIN_GOOGLETEST_SOURCE_DIR "/usr/src/googletest" CACHE PATH
  "GoogleTest sources, built from source when cross-compiling for a hosted target")

if(SCOPEKIN_BARE_METAL)
  set(SCOPEKIN_HAS_GTEST OFF)
elseif(CMAKE_CROSSCOMPILING)
  if(NOT EXISTS "${SCOPEKIN_GOOGLETEST_SOURCE_DIR}/CMakeLists.txt")
    message(FATAL_ERROR "GoogleTest sources not found in ${SCOPEKIN_GOOGLETEST_SOURCE_DIR} "
                        "(Debian package 'googletest', pulled in by libgtest-dev)")
  endif()
  set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
  set(gtest_force_shared_crt ON CACHE BOOL "" FORCE)
  add_subdirectory("${SCOPEKIN_GOOGLETEST_SOURCE_DIR}"
                   "${CMAKE_BINARY_DIR}/_deps/googletest" EXCLUDE_FROM_ALL SYSTEM)
  # Third-party code: its warnings are not ours to fix.
  foreach(_gtest_target IN ITEMS gtest gtest_main gmock gmock_main)
    if(TARGET ${_gtest_target})
      target_compile_options(${_gtest_target} PRIVATE -w)
    endif()
  endforeach()
  set(SCOPEKIN_HAS_GTEST ON)
else()
  find_package(GTest REQUIRED CONFIG)
  set(SCOPEKIN_HAS_GTEST ON)
endif()

if(SCOPEKIN_HAS_GTEST)
  include(GoogleTest)
endif()
