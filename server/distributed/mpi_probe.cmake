# peakcast_probe_mpi(OK_VAR WHY_VAR): can distributed rendering be built here? Configures the
# probe project (probe/) in a child CMake, so a broken MPI install cannot fail peakcast's own
# configure; WHY_VAR gets one line on why not.
function(peakcast_probe_mpi ok_var why_var)
  set(args -S ${CMAKE_CURRENT_FUNCTION_LIST_DIR}/probe -B ${CMAKE_BINARY_DIR}/mpi-probe
           -DCMAKE_C_COMPILER=${CMAKE_C_COMPILER})
  # What a user may set to point FindMPI or the IceT search elsewhere goes to the probe too.
  foreach(v MPI_C_COMPILER MPI_HOME MPIEXEC_EXECUTABLE CMAKE_PREFIX_PATH CMAKE_DISABLE_FIND_PACKAGE_MPI ICET_INCLUDE_DIR ICET_CONFIG_DIR
            ICET_CORE_LIBRARY ICET_MPI_LIBRARY)
    if(${v})  # set, and not a -NOTFOUND left by an earlier search
      list(APPEND args "-D${v}=${${v}}")
    endif()
  endforeach()
  file(REMOVE_RECURSE ${CMAKE_BINARY_DIR}/mpi-probe)
  execute_process(COMMAND ${CMAKE_COMMAND} ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                  TIMEOUT 120)
  if(rc EQUAL 0)
    set(${ok_var} TRUE PARENT_SCOPE)
    set(${why_var} "" PARENT_SCOPE)
    return()
  endif()
  set(${ok_var} FALSE PARENT_SCOPE)
  # The probe's own line when it got that far; else the first line of CMake's error (FindMPI).
  string(REGEX MATCH "peakcast-probe: [^\n]*" why "${err}")
  if(why)
    string(REPLACE "peakcast-probe: " "" why "${why}")
  else()
    # FindMPI's own error: the line after "CMake Error ...:" and the path it names, if any.
    string(REGEX MATCH "CMake Error[^\n]*:\n+([^\n]*)\n+( *\"[^\n]*)?" why "${err}")
    if(why)
      string(REGEX REPLACE "[ \n]+" " " why "MPI install broken:${CMAKE_MATCH_1} ${CMAKE_MATCH_2}")
    else()
      set(why "the MPI probe failed (exit ${rc}); see ${CMAKE_BINARY_DIR}/mpi-probe")
    endif()
  endif()
  set(${why_var} "${why}" PARENT_SCOPE)
endfunction()
