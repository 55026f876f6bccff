# SIL tests read the repo's scenario files.
target_compile_definitions(sil_test_scenario_errors PRIVATE
  FD_DEFAULT_SCENARIO="${PROJECT_SOURCE_DIR}/sil/scenarios/default.json")
# The preempting run needs two cores of its own (the main loop and the
# interrupter thread that signals it): alone, ~20 s on 2 cores; beside
# another test the interrupter waits for a time slice and the run crawls.
set_tests_properties(sil/test_preempt PROPERTIES RUN_SERIAL TRUE TIMEOUT 600)
target_compile_definitions(sil_test_syr_foc PRIVATE
  FD_SYR_SCENARIO="${PROJECT_SOURCE_DIR}/sil/scenarios/syr_1k1_speed_load.json")
# docs/scenarios.md's key reference is the key table's (sil/runner/scenario_key_table.h)
add_test(NAME sil/scenario_keys_doc
         COMMAND fluxdrive-sil --keys-doc ${PROJECT_SOURCE_DIR}/docs/scenarios.md)
