# Bad input at the kdet command line (issue 6): every malformed or invalid mesh gives exit code 1
# and one line on stderr naming the file (analyze: one per file plus a summary); nothing is printed on stdout. Run as
# `cmake -DKDET=<exe> -DWORK=<dir> -DCASE=<files|meshes> -P cli_bad_input.cmake`.
# (tests/cli_tests.cmake covers usage errors and missing files.)

if(NOT KDET OR NOT WORK OR NOT CASE)
  message(FATAL_ERROR "usage: cmake -DKDET=<kdet> -DWORK=<dir> -DCASE=<case> -P cli_bad_input.cmake")
endif()
file(MAKE_DIRECTORY "${WORK}")
set(good "${WORK}/good.obj")
file(WRITE "${good}" "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")

# reject(<file name> <content> <regex on stderr>): the file fails in every command that reads it.
function(reject name content err)
  set(p "${WORK}/${name}")
  file(WRITE "${p}" "${content}")
  foreach(args "self;${p}" "collide;${p};${good}" "collide;${good};${p}" "analyze;--quiet;${p}")
    execute_process(COMMAND "${KDET}" ${args} RESULT_VARIABLE rc OUTPUT_VARIABLE out
                    ERROR_VARIABLE err_text TIMEOUT 120)
    if(NOT rc STREQUAL "1")
      message(FATAL_ERROR "kdet ${args}: exit code '${rc}', expected 1\nstdout:\n${out}\nstderr:\n${err_text}")
    endif()
    string(REGEX REPLACE "\n$" "" one "${err_text}")
    if(one MATCHES "\n" AND NOT args MATCHES "^analyze")  # analyze adds a summary line
      message(FATAL_ERROR "kdet ${args}: error message is not one line:\n${err_text}")
    endif()
    if(NOT err_text MATCHES "${name}" OR NOT err_text MATCHES "${err}")
      message(FATAL_ERROR "kdet ${args}: stderr does not name '${name}' and match '${err}':\n${err_text}")
    endif()
  endforeach()
endfunction()

if(CASE STREQUAL "files")
  reject(empty.obj "" "empty")
  reject(empty.ply "" "empty")
  reject(trunc.off "OFF\n3 1 0\n0 0 0\n1 0 0\n" "truncated|line")
  reject(header.ply "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nend_heder\n" ".")
  reject(noply.ply "plx\nformat ascii 1.0\nend_header\n" ".")
  reject(version.ply "ply\nformat ascii 2.0\nelement vertex 0\nend_header\n" ".")
  string(REPEAT " " 80 stl_header)
  # A binary STL whose count (0x07070707 triangles) disagrees with its 84-byte size. (Bytes
  # built with string(ASCII): CMake strings cannot hold NUL, and newer CMake rejects \u escapes.)
  string(ASCII 7 7 7 7 bad_count)
  reject(count.stl "${stl_header}${bad_count}" "disagrees|truncated")
  reject(huge.off "OFF\n4000000000 4000000000 0\n0 0 0\n" ".")
elseif(CASE STREQUAL "meshes")
  reject(nan.obj "v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n" "nan|finite|coordinate")
  reject(inf.off "OFF\n3 1 0\n0 0 inf\n1 0 0\n0 1 0\n3 0 1 2\n" "inf|finite|coordinate")
  reject(overflow.obj "v 0 0 1e309\nv 1 0 0\nv 0 1 0\nf 1 2 3\n" "finite")
  # Finite, but beyond the range where the hierarchy and the exact predicates hold (a query of
  # such a mesh did not finish before); the reader takes it, the commands refuse it.
  reject(scale.obj "v 0 0 1e200\nv 1 0 0\nv 0 1 0\nf 1 2 3\n" "vertex 0.*2\\^330")
  reject(tiny.obj "v 0 0 1e-200\nv 1e-200 0 0\nv 0 1e-200 0\nf 1 2 3\n" "2\\^-247")
  reject(range.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n" "out of range")
  reject(negative.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -4\n" "before the first vertex")
  reject(zero.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n" "non-zero")
  reject(word.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 two 3\n" "bad face index")
  reject(two.obj "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\n" "need at least 3")
  reject(two.off "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n" ".")
  reject(range.off "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n" ".")
  reject(negative.ply "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n" "negative")
else()
  message(FATAL_ERROR "unknown CASE '${CASE}'")
endif()
