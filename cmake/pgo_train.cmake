# The training run of the SIL's profile-guided optimisation (cmake/pgo.cmake):
#   cmake -DRUNNER=... -DPROFILE=dir -DSTAMP=file -DSCENARIOS=dir -DTRAIN="a;b" -P pgo_train.cmake
# A fresh profile (the counters of earlier runs removed), each scenario once
# without a log (the runner's --bench path), then STAMP = the digest of the
# profile, rewritten only when it differs (the objects that depend on it
# are recompiled only then). The runs are deterministic: the same sources
# give the same profile.
file(GLOB old "${PROFILE}/*.gcda")
if(old)
  file(REMOVE ${old})
endif()
foreach(s IN LISTS TRAIN)
  execute_process(COMMAND ${RUNNER} ${SCENARIOS}/${s}.json --bench RESULT_VARIABLE rc
                  OUTPUT_QUIET)
  if(NOT rc EQUAL 0) # a partial profile is still a profile: the build goes on
    message(WARNING "PGO training: ${RUNNER} ${s}.json --bench failed (${rc})")
  endif()
endforeach()
file(GLOB gcda "${PROFILE}/*.gcda")
list(SORT gcda)
set(digest "")
foreach(f IN LISTS gcda)
  file(SHA256 ${f} h)
  get_filename_component(n ${f} NAME)
  string(APPEND digest "${h} ${n}\n")
endforeach()
file(WRITE ${STAMP}.new "${digest}")
execute_process(COMMAND ${CMAKE_COMMAND} -E copy_if_different ${STAMP}.new ${STAMP})
file(REMOVE ${STAMP}.new)
