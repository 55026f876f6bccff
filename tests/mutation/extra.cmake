# The mutation check (scripts/mutation_check.py, docs/mutation.md): each
# mutant of tests/mutation/mutants.json, a deliberate bug in the firmware,
# must make at least one of its acceptance or SIL tests fail. Runs on a
# host-release copy of the source tree in <build>/mutation (kept between
# runs: the copy is synced and rebuilt incrementally); the caller's tree is
# never written. Also fails when docs/mutation.md no longer lists exactly
# these mutants.
if(FD_PYTHON)
  add_test(NAME mutation/acceptance
           COMMAND ${FD_PYTHON} ${PROJECT_SOURCE_DIR}/scripts/mutation_check.py
                   --workdir ${CMAKE_BINARY_DIR}/mutation --python ${FD_PYTHON}
                   --check-markdown ${PROJECT_SOURCE_DIR}/docs/mutation.md
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(mutation/acceptance PROPERTIES LABELS mutation TIMEOUT 1800)
else()
  message(STATUS "FD_PYTHON not set: mutation/acceptance not registered (scripts/test.sh sets it)")
endif()
