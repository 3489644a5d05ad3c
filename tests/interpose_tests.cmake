# Checks of libkdet_fcl_interpose.so under an unmodified FCL program (examples/unmodified_fcl.cpp,
# linked with libfcl alone), run as
#   cmake -DAPP=<example_unmodified_fcl> -DSHIM=<libkdet_fcl_interpose.so> -DWORK=<dir> -DCASE=<case> -P
# CASE cpu: the program alone, under the library, and under the library switched off; bad
#   settings. CASE cuda: the library with KDET_FCL_INTERPOSE_BACKEND=cuda (the GPU where there is
#   one, else the CPU after a one-line notice).

if(NOT APP OR NOT SHIM OR NOT WORK OR NOT CASE)
  message(FATAL_ERROR "usage: cmake -DAPP=<exe> -DSHIM=<so> -DWORK=<dir> -DCASE=cpu|cuda -P interpose_tests.cmake")
endif()
file(MAKE_DIRECTORY "${WORK}")

# Under AddressSanitizer (scripts/sanitize.sh) the preloaded library comes before the sanitizer's
# runtime, which ASan checks by default.
set(asan "")
if(DEFINED ENV{ASAN_OPTIONS})
  set(asan "ASAN_OPTIONS=$ENV{ASAN_OPTIONS}:verify_asan_link_order=0")
endif()

# run(<prefix> [VAR=value...]): runs the program with the environment given (under the library
# unless NOPRELOAD), sets <prefix>_out and <prefix>_err, fails on a non-zero exit.
function(run prefix)
  cmake_parse_arguments(R "NOPRELOAD" "" "" ${ARGN})
  set(env ${R_UNPARSED_ARGUMENTS})
  if(NOT R_NOPRELOAD)
    list(APPEND env "LD_PRELOAD=${SHIM}" "KDET_FCL_INTERPOSE_STATS=1")
    if(asan)
      list(APPEND env "${asan}")
    endif()
  endif()
  execute_process(COMMAND ${CMAKE_COMMAND} -E env ${env} "${APP}"
                  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err TIMEOUT 240)
  file(WRITE "${WORK}/${prefix}.out" "${out}")
  file(WRITE "${WORK}/${prefix}.err" "${err}")
  if(NOT rc STREQUAL "0")
    message(FATAL_ERROR "${prefix} (${env}): exit code '${rc}'\nstdout:\n${out}\nstderr:\n${err}")
  endif()
  set(${prefix}_out "${out}" PARENT_SCOPE)
  set(${prefix}_err "${err}" PARENT_SCOPE)
endfunction()

function(require text regex what)
  if(NOT text MATCHES "${regex}")
    message(FATAL_ERROR "${what}: no match for '${regex}' in:\n${text}")
  endif()
endfunction()

function(forbid text regex what)
  if(text MATCHES "${regex}")
    message(FATAL_ERROR "${what}: unexpected '${regex}' in:\n${text}")
  endif()
endfunction()

# The program's own run: FCL has no OBB-RSS function, so its mixed pair finds nothing.
run(plain NOPRELOAD)
require("${plain_out}" "mixed 0: collision 0, contacts 0" "FCL alone")
require("${plain_err}" "collision function between node type [0-9]+ and node type [0-9]+ is not supported" "FCL alone (its warning for the mixed pair)")
string(REGEX REPLACE "mixed 0:[^\n]*\n" "" plain_rest "${plain_out}")

# Under the library: every line the same as FCL's except the mixed pair, which kDet decides
# like the same pair at the same pose with equal BV types ("objects 0").
function(check_kdet prefix backend)
  set(out "${${prefix}_out}")
  set(err "${${prefix}_err}")
  string(REGEX REPLACE "mixed 0:[^\n]*\n" "" rest "${out}")
  if(NOT rest STREQUAL plain_rest)
    message(FATAL_ERROR "${prefix}: results differ from FCL's\nFCL:\n${plain_out}\nunder the library:\n${out}")
  endif()
  string(REGEX MATCH "objects 0: ([^\n]*)" m "${out}")
  set(objects0 "${CMAKE_MATCH_1}")
  require("${objects0}" "^collision 1, contacts [1-9]" "${prefix}: objects 0")
  require("${out}" "mixed 0: ${objects0}\n" "${prefix}: the mixed pair through kDet")
  forbid("${err}" "collision function between node type" "${prefix}: the mixed pair went to FCL")
  # The scaled pose is refused by kDet and goes to FCL: one notice.
  require("${err}" "the rotation is not orthonormal[^\n]*this pair went to FCL" "${prefix}")
  string(REGEX MATCHALL "this pair went to FCL" notices "${err}")
  list(LENGTH notices n)
  if(NOT n EQUAL 1)
    message(FATAL_ERROR "${prefix}: ${n} fallback notices, expected 1:\n${err}")
  endif()
  string(REGEX MATCH "on; backend ${backend}; cache (checksum|trust); fcl::collide calls ([0-9]+), mesh pairs by kDet ([0-9]+), forwarded to FCL ([0-9]+), fell back to FCL ([0-9]+); geometry destructor calls ([0-9]+); cache entries at exit ([0-9]+)" s "${err}")
  if(NOT s)
    message(FATAL_ERROR "${prefix}: no statistics line for backend ${backend}:\n${err}")
  endif()
  set(calls ${CMAKE_MATCH_2})
  set(kdet ${CMAKE_MATCH_3})
  set(forwarded ${CMAKE_MATCH_4})
  set(fallbacks ${CMAKE_MATCH_5})
  set(destroyed ${CMAKE_MATCH_6})
  set(left ${CMAKE_MATCH_7})
  if(NOT CMAKE_MATCH_1 STREQUAL "checksum")
    message(FATAL_ERROR "${prefix}: cache ${CMAKE_MATCH_1}, expected checksum:\n${err}")
  endif()
  # The program's mesh-mesh calls: 24 (objects, first) + 8 (geometries) + 4 (deforming) + 2
  # (replaced) + 30 (lifetime) + 1 (mixed) + the manager's mesh pairs; 2 shape calls at least go
  # to FCL.
  math(EXPR sum "${kdet} + ${forwarded} + ${fallbacks}")
  if(kdet LESS 69 OR forwarded LESS 2 OR NOT fallbacks EQUAL 1 OR NOT sum EQUAL calls)
    message(FATAL_ERROR "${prefix}: calls ${calls}, kDet ${kdet}, forwarded ${forwarded}, fallbacks ${fallbacks}")
  endif()
  # 67 meshes and 3 shapes are destroyed before exit, and each took its cache entry along.
  if(destroyed LESS 70 OR NOT left EQUAL 0)
    message(FATAL_ERROR "${prefix}: destructor calls ${destroyed}, cache entries left ${left}:\n${err}")
  endif()
endfunction()

if(CASE STREQUAL "cpu")
  run(kdet)
  check_kdet(kdet cpu)

  # Switched off: FCL's results exactly, nothing counted.
  run(off KDET_FCL_INTERPOSE=0)
  if(NOT off_out STREQUAL plain_out)
    message(FATAL_ERROR "KDET_FCL_INTERPOSE=0: results differ from FCL's\n${off_out}")
  endif()
  require("${off_err}" "off \\(KDET_FCL_INTERPOSE=0\\); backend cpu; cache checksum; fcl::collide calls 0, mesh pairs by kDet 0" "off")

  # Bad settings: a one-line notice each, and the defaults.
  run(bad KDET_FCL_INTERPOSE_BACKEND=gpu KDET_FCL_INTERPOSE_THREADS=many
          KDET_FCL_INTERPOSE_CACHE=sometimes)
  require("${bad_err}" "KDET_FCL_INTERPOSE_BACKEND='gpu' is not cpu, cuda or auto; using cpu" "bad backend")
  require("${bad_err}" "KDET_FCL_INTERPOSE_THREADS='many' is not a thread count" "bad threads")
  require("${bad_err}" "KDET_FCL_INTERPOSE_CACHE='sometimes' is not checksum or trust; using checksum" "bad cache")
  check_kdet(bad cpu)

  # The cache on trust (pointers and counts only): the same as the checksum's results, except
  # after FCL's replace calls, which write in place. Those it misses by design: the replaced
  # model's query still finds the pairs of its first shape.
  run(trust KDET_FCL_INTERPOSE_CACHE=trust)
  string(REGEX REPLACE "replaced 1:[^\n]*\n" "" trust_rest "${trust_out}")
  string(REGEX REPLACE "replaced 1:[^\n]*\n" "" kdet_rest "${kdet_out}")
  if(NOT trust_rest STREQUAL kdet_rest)
    message(FATAL_ERROR "trust: results differ from the checksum's\n${trust_out}\n${kdet_out}")
  endif()
  string(REGEX MATCH "replaced 0: ([^\n]*)" m "${trust_out}")
  require("${trust_out}" "replaced 1: ${CMAKE_MATCH_1}\n" "trust: the replaced model's stale hash")
  string(REGEX MATCH "replaced 1: ([^\n]*)" m "${plain_out}")
  forbid("${trust_out}" "replaced 1: ${CMAKE_MATCH_1}\n" "trust: a replace seen without the checksum")
  require("${trust_err}" "on; backend cpu; cache trust; " "trust: the statistics line")

  # One thread: the same pairs.
  run(one KDET_FCL_INTERPOSE_THREADS=1)
  check_kdet(one cpu)
elseif(CASE STREQUAL "cuda")
  run(gpu KDET_FCL_INTERPOSE_BACKEND=cuda)
  if(gpu_err MATCHES "KDET_FCL_INTERPOSE_BACKEND=cuda, but (no CUDA device was found|this kdet_fcl was built without CUDA); the CPU backend runs instead")
    message(STATUS "no CUDA device: checked the notice and the CPU backend")
    check_kdet(gpu cpu)
  else()
    check_kdet(gpu cuda)
    # A KDET_FCL_CUDA_DEVICE that names no device: a notice, and the CPU backend answers.
    run(nodev KDET_FCL_INTERPOSE_BACKEND=cuda KDET_FCL_CUDA_DEVICE=1023)
    require("${nodev_err}" "KDET_FCL_CUDA_DEVICE=1023 names CUDA device 1023, but this machine has"
            "a device that does not exist")
    require("${nodev_err}" "the CPU backend runs instead" "a device that does not exist")
    check_kdet(nodev cpu)
  endif()
else()
  message(FATAL_ERROR "unknown CASE '${CASE}'")
endif()
