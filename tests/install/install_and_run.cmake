# cmake -P script behind tests/install: installs BUILD_DIR into WORK_DIR/prefix, configures and builds
# EXAMPLES_DIR against that prefix alone, and runs hello_wind. Fails when the install lays out more
# headers than the two public ones, when the consumer finds gust anywhere but in the prefix, when the
# example does not build warning-free, when hello_wind fails or prints a validation message, or when its
# output lacks the wind it must print (a point outside the domain gets exactly the ambient wind). A build
# without OpenVDB (WITH_OPENVDB off) must install a package that neither ships the OpenVDB writer nor asks
# for OpenVDB: the consumer is configured with OpenVDB made unfindable.
foreach(var BUILD_DIR EXAMPLES_DIR WORK_DIR CONFIG GENERATOR CXX_COMPILER WITH_OPENVDB)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "install_and_run.cmake needs -D${var}=...")
  endif()
endforeach()

set(prefix ${WORK_DIR}/prefix)
set(consumer ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})

function(run_step name)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE out)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "${name} failed (${rc}):\n${out}")
  endif()
  set(step_output "${out}" PARENT_SCOPE)
endfunction()

run_step("cmake --install" ${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix} --config ${CONFIG})

file(GLOB_RECURSE headers RELATIVE ${prefix}/include ${prefix}/include/*)
list(SORT headers)
if(NOT headers STREQUAL "gust/gust.h;gust/gust.hpp;gust/gust_wind.glsl")
  message(FATAL_ERROR "the install's include/ should hold gust/gust.h, gust/gust.hpp and gust/gust_wind.glsl "
                      "only, holds: ${headers}")
endif()

set(configure_args -S ${EXAMPLES_DIR} -B ${consumer} -G ${GENERATOR}
  -DCMAKE_BUILD_TYPE=${CONFIG}
  -DCMAKE_PREFIX_PATH=${prefix}
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
  -DCMAKE_CXX_COMPILER=${CXX_COMPILER}
  "-DCMAKE_CXX_FLAGS=${CXX_FLAGS}")
if(NOT WITH_OPENVDB)
  file(GLOB vdb_archives ${prefix}/lib*/libgust_vdb.a)
  if(vdb_archives)
    message(FATAL_ERROR "a build without OpenVDB installed the OpenVDB writer: ${vdb_archives}")
  endif()
  file(GLOB_RECURSE target_files ${prefix}/lib*/cmake/gust/gustTargets*.cmake)
  foreach(target_file IN LISTS target_files)
    file(STRINGS ${target_file} mentions REGEX "OpenVDB|openvdb|gust_vdb")
    if(mentions)
      message(FATAL_ERROR "${target_file} of a build without OpenVDB links OpenVDB: ${mentions}")
    endif()
  endforeach()
  list(APPEND configure_args -DCMAKE_DISABLE_FIND_PACKAGE_OpenVDB=ON)
endif()
if(MAKE_PROGRAM)
  list(APPEND configure_args -DCMAKE_MAKE_PROGRAM=${MAKE_PROGRAM})
endif()
run_step("configuring examples/" ${CMAKE_COMMAND} ${configure_args})
file(STRINGS ${consumer}/CMakeCache.txt gust_dir REGEX "^gust_DIR:")
string(REGEX REPLACE "^gust_DIR:[A-Z]+=" "" gust_dir "${gust_dir}")
cmake_path(IS_PREFIX prefix "${gust_dir}" NORMALIZE from_prefix)
if(NOT from_prefix)
  message(FATAL_ERROR "examples/ found gust in ${gust_dir}, not in ${prefix}")
endif()

run_step("building hello_wind" ${CMAKE_COMMAND} --build ${consumer} --config ${CONFIG})
if(step_output MATCHES "warning:")
  message(FATAL_ERROR "hello_wind built with warnings:\n${step_output}")
endif()

find_program(hello_wind hello_wind PATHS ${consumer} ${consumer}/${CONFIG} NO_DEFAULT_PATH REQUIRED)
run_step("hello_wind --validation" ${hello_wind} --validation)
message("${step_output}")
if(step_output MATCHES "VUID-|UNASSIGNED-|Validation (Error|Warning|Performance)|gust error:")
  message(FATAL_ERROR "hello_wind reported a validation message or an error")
endif()
if(step_output MATCHES "[(, ]-?(nan|inf)[,)]")
  message(FATAL_ERROR "hello_wind printed a non-finite wind")
endif()
foreach(expected
    "wind at \\(-10, 1, 0\\): \\(-?[0-9]+\\.[0-9]+, -?[0-9]+\\.[0-9]+, -?[0-9]+\\.[0-9]+\\) m/s"
    "wind at \\(0, 2, 3\\): \\(-?[0-9]+\\.[0-9]+, -?[0-9]+\\.[0-9]+, -?[0-9]+\\.[0-9]+\\) m/s"
    # Outside the domain the wind is the ambient wind (gust.hpp, System::query).
    "wind at \\(100, 0, 0\\): \\(4\\.00, -?0\\.00, -?0\\.00\\) m/s"
    "wind_at \\(0, 2, 3\\): direction \\(-?[0-9.]+, -?[0-9.]+, -?[0-9.]+\\), speed [0-9.]+ m/s, gust [0-9.]+ m/s")
  if(NOT step_output MATCHES "${expected}")
    message(FATAL_ERROR "hello_wind's output lacks a line matching: ${expected}")
  endif()
endforeach()
