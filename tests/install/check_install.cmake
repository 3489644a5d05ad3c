# cmake -P script: install a kdet_fcl build tree into a scratch prefix, then configure, build
# and run tests/install/consumer against that prefix. Fails (FATAL_ERROR) on any step.
#
#   cmake -DBUILD_DIR=<kdet_fcl build> [-DWORK_DIR=<scratch>] [-DCONFIG=Release]
#         [-DCONSUMER_SOURCE_DIR=<dir>] [-DCMAKE_GENERATOR=<gen>] [-DCXX_COMPILER=<c++>]
#         -P tests/install/check_install.cmake
cmake_minimum_required(VERSION 3.16)

if(NOT BUILD_DIR)
  message(FATAL_ERROR "check_install: pass -DBUILD_DIR=<kdet_fcl build directory>")
endif()
if(NOT EXISTS "${BUILD_DIR}/cmake_install.cmake")
  message(FATAL_ERROR "check_install: ${BUILD_DIR} is not a configured kdet_fcl build tree")
endif()
if(NOT CONSUMER_SOURCE_DIR)
  set(CONSUMER_SOURCE_DIR "${CMAKE_CURRENT_LIST_DIR}/consumer")
endif()
if(NOT WORK_DIR)
  set(WORK_DIR "${BUILD_DIR}/install_consumer")
endif()
if(NOT CONFIG)
  set(CONFIG Release)
endif()

set(prefix "${WORK_DIR}/prefix")
set(consumer_build "${WORK_DIR}/build")
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")

# run(<step> <command...>): run a command, echo it, fail loudly on a non-zero exit.
function(run step)
  message(STATUS "check_install [${step}]: ${ARGN}")
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "check_install: step '${step}' failed (exit ${rc}): ${ARGN}")
  endif()
endfunction()

# 1. Install.
run(install "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${prefix}" --config "${CONFIG}")

file(GLOB_RECURSE config_files "${prefix}/*/kdet_fclConfig.cmake")
if(NOT config_files)
  message(FATAL_ERROR "check_install: no kdet_fclConfig.cmake under ${prefix}")
endif()
list(GET config_files 0 config_file)
get_filename_component(config_dir "${config_file}" DIRECTORY)

# 2. The exported link interface must not leak the private dependencies. (CMake may still
#    name a private shared library in IMPORTED_LINK_DEPENDENT_LIBRARIES: a runtime hint for the
#    linker's rpath-link, not something the consumer links.)
file(GLOB target_files "${config_dir}/kdet_fclTargets*.cmake")
foreach(f IN LISTS target_files)
  file(STRINGS "${f}" interface_lines REGEX "INTERFACE_LINK_LIBRARIES|IMPORTED_LINK_INTERFACE")
  foreach(private IN ITEMS tinyobjloader cudart CUDA::)
    string(FIND "${interface_lines}" "${private}" pos)
    if(NOT pos EQUAL -1)
      message(FATAL_ERROR "check_install: ${f} exports the private dependency '${private}': "
                          "${interface_lines}")
    endif()
  endforeach()
endforeach()
if(NOT EXISTS "${prefix}/include/kdet_fcl/kdet_fcl.h")
  message(FATAL_ERROR "check_install: include/kdet_fcl/kdet_fcl.h was not installed")
endif()

# 2b. The installed interposer (when built) finds the installed library beside it and takes an
#     unmodified FCL program's mixed-BV pair, which FCL alone refuses (tests/interpose_tests.cmake).
if(INTERPOSE_APP)
  file(GLOB_RECURSE shim "${prefix}/*/libkdet_fcl_interpose.so")
  if(NOT shim)
    message(FATAL_ERROR "check_install: libkdet_fcl_interpose.so was not installed")
  endif()
  list(GET shim 0 shim)
  message(STATUS "check_install [interpose]: LD_PRELOAD=${shim} ${INTERPOSE_APP}")
  set(asan "")
  if(DEFINED ENV{ASAN_OPTIONS})
    set(asan "ASAN_OPTIONS=$ENV{ASAN_OPTIONS}:verify_asan_link_order=0")
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env "LD_PRELOAD=${shim}" "KDET_FCL_INTERPOSE_STATS=1"
                          ${asan} "${INTERPOSE_APP}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "mixed 0: collision 1" OR NOT err MATCHES "kdet_fcl interpose: on")
    message(FATAL_ERROR "check_install: the installed interposer did not run (exit ${rc}):\n${out}\n${err}")
  endif()
endif()

# 2c. The installed Python module (when built) imports from the prefix's site directory alone
#     (its rpath finds the installed libkdet_fcl.so) and answers a query.
if(PYTHON_EXE)
  file(GLOB_RECURSE py_init "${prefix}/__init__.py")
  list(FILTER py_init INCLUDE REGEX "/kdet_fcl/__init__.py$")
  file(GLOB_RECURSE py_ext "${prefix}/_kdet_fcl*.so")
  if(NOT py_init OR NOT py_ext)
    message(FATAL_ERROR "check_install: the Python package kdet_fcl was not installed")
  endif()
  list(GET py_init 0 py_init)
  get_filename_component(py_pkg "${py_init}" DIRECTORY)
  get_filename_component(py_site "${py_pkg}" DIRECTORY)
  set(py_check "import kdet_fcl, numpy as np; from kdet_fcl import fcl
assert kdet_fcl.__file__.startswith('${py_site}'), kdet_fcl.__file__
v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], float)
a = kdet_fcl.Mesh(v, [[0, 1, 2]])
b = kdet_fcl.Mesh(v, [[0, 1, 2]], rotation=[[1, 0, 0], [0, 0, -1], [0, 1, 0]], translation=[0.1, 0.3, -0.2])
assert kdet_fcl.intersect(a, b).tolist() == [[0, 0]]
print('python module OK')")
  message(STATUS "check_install [python]: PYTHONPATH=${py_site} ${PYTHON_EXE}")
  execute_process(COMMAND ${CMAKE_COMMAND} -E env "PYTHONPATH=${py_site}" "PYTHONDONTWRITEBYTECODE=1"
                          "${PYTHON_EXE}" -c "${py_check}"
                  WORKING_DIRECTORY "${WORK_DIR}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0 OR NOT out MATCHES "python module OK")
    message(FATAL_ERROR "check_install: the installed Python module failed (exit ${rc}):\n${out}\n${err}")
  endif()
endif()

# 3. Configure the consumer against the prefix only (no package registry, no build tree).
set(configure_args
  -S "${CONSUMER_SOURCE_DIR}" -B "${consumer_build}"
  "-DCMAKE_PREFIX_PATH=${prefix}"
  "-DKDET_FCL_EXPECTED_PREFIX=${prefix}"
  "-DCMAKE_BUILD_TYPE=${CONFIG}"
  -DCMAKE_FIND_USE_PACKAGE_REGISTRY=OFF
  -DCMAKE_FIND_PACKAGE_NO_PACKAGE_REGISTRY=ON)
if(DEPS_PREFIX_PATH)
  # The dependencies' own prefixes go through the environment (a ';' cannot live inside one
  # argument of a CMake list); kdet_fcl itself is still found in ${prefix} only.
  list(JOIN DEPS_PREFIX_PATH ":" deps)
  set(ENV{CMAKE_PREFIX_PATH} "${deps}")
endif()
foreach(var IN ITEMS ccd_DIR octomap_DIR)
  if(${var})
    list(APPEND configure_args "-D${var}=${${var}}")
  endif()
endforeach()
if(POLICY_VERSION_MINIMUM)
  list(APPEND configure_args "-DCMAKE_POLICY_VERSION_MINIMUM=${POLICY_VERSION_MINIMUM}")
endif()
if(CMAKE_GENERATOR)
  list(APPEND configure_args -G "${CMAKE_GENERATOR}")
endif()
if(CXX_COMPILER)
  list(APPEND configure_args "-DCMAKE_CXX_COMPILER=${CXX_COMPILER}")
endif()
run(configure "${CMAKE_COMMAND}" ${configure_args})

# 4. Build.
run(build "${CMAKE_COMMAND}" --build "${consumer_build}" --config "${CONFIG}")

# 5. Run.
set(app "${consumer_build}/app")
if(NOT EXISTS "${app}")
  set(app "${consumer_build}/${CONFIG}/app")
endif()
if(NOT EXISTS "${app}")
  message(FATAL_ERROR "check_install: the consumer program was not built in ${consumer_build}")
endif()
run(run "${app}")

message(STATUS "check_install: OK (installed to ${prefix}, consumer built and ran)")
