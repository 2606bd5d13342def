# scopekin_debian_python3_runs(<out_var> <python statement>)
#
# Sets <out_var> TRUE when Debian's /usr/bin/python3 (cached as SCOPEKIN_PLOTS_PYTHON3) exists and
# runs the statement (e.g. an import of the Debian packages a Python test needs), FALSE otherwise.
include_guard(GLOBAL)

function(scopekin_debian_python3_runs out statement)
  find_program(SCOPEKIN_PLOTS_PYTHON3 python3 PATHS /usr/bin NO_DEFAULT_PATH
               DOC "Debian's python3 (with python3-matplotlib), used by the host_sim Python tests")
  set(_ok FALSE)
  if(SCOPEKIN_PLOTS_PYTHON3)
    execute_process(COMMAND ${SCOPEKIN_PLOTS_PYTHON3} -c "${statement}"
                    RESULT_VARIABLE _rc OUTPUT_QUIET ERROR_QUIET)
    if(_rc EQUAL 0)
      set(_ok TRUE)
    endif()
  endif()
  set(${out} ${_ok} PARENT_SCOPE)
endfunction()
