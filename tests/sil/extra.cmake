# SIL tests read the repo's scenario files.
target_compile_definitions(sil_test_scenario_errors PRIVATE
  FD_DEFAULT_SCENARIO="${PROJECT_SOURCE_DIR}/sil/scenarios/default.json")
