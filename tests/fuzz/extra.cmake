# The libFuzzer harnesses (docs/fuzzing.md): fuzz/build configures and builds
# the clang tree (tests/fuzz/CMakeLists.txt) once, as the fixture of the
# short runs fuzz/<harness> (10 s each on the committed corpus).
set(FD_FUZZ_BUILD ${CMAKE_BINARY_DIR}/fuzz)
add_test(NAME fuzz/build
         COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/build_fuzz.sh ${PROJECT_SOURCE_DIR}
                 ${FD_FUZZ_BUILD})
set_tests_properties(fuzz/build PROPERTIES LABELS fuzz TIMEOUT 900
                     FIXTURES_SETUP fd_fuzz_tree)
foreach(h fuzz_can fuzz_scenario fuzz_fluxmap)
  add_test(NAME fuzz/${h}
           COMMAND ${CMAKE_CURRENT_SOURCE_DIR}/fuzz/run_fuzz.sh ${PROJECT_SOURCE_DIR}
                   ${FD_FUZZ_BUILD} ${h} 10)
  set_tests_properties(fuzz/${h} PROPERTIES LABELS fuzz TIMEOUT 120
                       FIXTURES_REQUIRED fd_fuzz_tree)
endforeach()
