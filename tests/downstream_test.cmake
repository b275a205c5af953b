# Installs liedyn from BINARY_DIR into WORK_DIR/prefix, configures and builds the
# downstream project SOURCE_DIR/examples against it (find_package(liedyn)), runs its examples.
#   cmake -DSOURCE_DIR=... -DBINARY_DIR=... -DWORK_DIR=... -P downstream_test.cmake
cmake_minimum_required(VERSION 3.25)

foreach(var SOURCE_DIR BINARY_DIR WORK_DIR)
  if(NOT DEFINED ${var} OR "${${var}}" STREQUAL "")
    message(FATAL_ERROR "downstream_test: -D${var}=... is required")
  endif()
endforeach()

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
# Start clean so that a stale install or cache cannot hide a broken export.
file(REMOVE_RECURSE ${prefix} ${build})
file(MAKE_DIRECTORY ${WORK_DIR})

# Runs a command, echoes its output, FATAL_ERRORs on a non-zero exit status.
function(run_step name)
  message(STATUS "downstream_test: ${name}: ${ARGN}")
  execute_process(COMMAND ${ARGN}
    RESULT_VARIABLE result
    OUTPUT_VARIABLE output
    ERROR_VARIABLE output)
  message("${output}")
  if(NOT result EQUAL 0)
    message(FATAL_ERROR "downstream_test: ${name} failed (${result})")
  endif()
endfunction()

# Same build type as the tree being installed (single-config generators); the install and
# the example use it too.
set(config_args)
set(install_config)
if(EXISTS ${BINARY_DIR}/CMakeCache.txt)
  file(STRINGS ${BINARY_DIR}/CMakeCache.txt build_type_line REGEX "^CMAKE_BUILD_TYPE:")
  string(REGEX REPLACE "^CMAKE_BUILD_TYPE:[A-Z]+=" "" build_type "${build_type_line}")
  if(NOT build_type STREQUAL "")
    list(APPEND config_args -DCMAKE_BUILD_TYPE=${build_type})
    set(install_config --config ${build_type})
  endif()
  file(STRINGS ${BINARY_DIR}/CMakeCache.txt compiler_line REGEX "^CMAKE_CXX_COMPILER:")
  string(REGEX REPLACE "^CMAKE_CXX_COMPILER:[A-Z]+=" "" cxx_compiler "${compiler_line}")
  if(NOT cxx_compiler STREQUAL "")
    list(APPEND config_args -DCMAKE_CXX_COMPILER=${cxx_compiler})
  endif()
endif()

run_step(install ${CMAKE_COMMAND} --install ${BINARY_DIR} --prefix ${prefix} ${install_config})

foreach(f include/liedyn/solvers/simulator.hpp include/liedyn/lib/model.hpp)
  if(NOT EXISTS ${prefix}/${f})
    message(FATAL_ERROR "downstream_test: ${prefix}/${f} was not installed")
  endif()
endforeach()

run_step(configure ${CMAKE_COMMAND} -S ${SOURCE_DIR}/examples -B ${build}
  -DCMAKE_PREFIX_PATH=${prefix} ${config_args})
run_step(build ${CMAKE_COMMAND} --build ${build} ${install_config})

# Each example checks its own results and exits non-zero when they do not hold.
foreach(example spin_up rotation_averaging attitude_control)
  set(exe ${build}/${example})
  if(NOT EXISTS ${exe} AND build_type)
    set(exe ${build}/${build_type}/${example})
  endif()
  run_step(${example} ${exe})
endforeach()
message(STATUS "downstream_test: passed")
