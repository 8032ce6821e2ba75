# CTest "downstream_package": installs the built project into a prefix inside the build tree,
# then configures, builds and runs tests/downstream against that install.
#   cmake -DPROJECT_BINARY_DIR=... -DDOWNSTREAM_SOURCE_DIR=... -DWORK_DIR=... -DGENERATOR=...
#         -DC_COMPILER=... -DCXX_COMPILER=... -DBUILD_TYPE=... [-DBUILD_TYPE_FLAGS=...]
#         [-DSANITIZE_FLAGS=...]
#         -P downstream_package.cmake
cmake_minimum_required(VERSION 3.22)

foreach(var PROJECT_BINARY_DIR DOWNSTREAM_SOURCE_DIR WORK_DIR GENERATOR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "downstream_package.cmake: -D${var}=... is required")
  endif()
endforeach()

function(run step)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "downstream_package: ${step} failed (${rc})")
  endif()
endfunction()

set(prefix ${WORK_DIR}/prefix)
set(build ${WORK_DIR}/build)
file(REMOVE_RECURSE ${WORK_DIR})

run(install ${CMAKE_COMMAND} --install ${PROJECT_BINARY_DIR} --prefix ${prefix})

# A static library built with sanitizers needs them in the program that links it too.
set(flags)
if(SANITIZE_FLAGS)
  set(flags "-DCMAKE_CXX_FLAGS=${SANITIZE_FLAGS}")
endif()
if(BUILD_TYPE AND BUILD_TYPE_FLAGS)
  string(TOUPPER "${BUILD_TYPE}" type)
  list(APPEND flags "-DCMAKE_CXX_FLAGS_${type}=${BUILD_TYPE_FLAGS}")
endif()
run(configure ${CMAKE_COMMAND} -S ${DOWNSTREAM_SOURCE_DIR} -B ${build} -G ${GENERATOR}
    -DCMAKE_BUILD_TYPE=${BUILD_TYPE} -DCMAKE_C_COMPILER=${C_COMPILER}
    -DCMAKE_CXX_COMPILER=${CXX_COMPILER} -DCMAKE_PREFIX_PATH=${prefix}
    -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON ${flags})
run(build ${CMAKE_COMMAND} --build ${build})
run(run ${build}/downstream)
run(run_core ${build}/downstream_core)
run(run_openni2 ${build}/downstream_openni2)
