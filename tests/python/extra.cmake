# pytest (tools package) with the venv from scripts/setup.sh; the SIL test
# uses this build's fluxdrive-sil.
set(FD_PYTHON "" CACHE FILEPATH "Python of the tools venv (scripts/setup.sh)")
if(FD_PYTHON)
  add_test(NAME python/pytest
           COMMAND ${FD_PYTHON} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/python
                   --ignore=${CMAKE_CURRENT_SOURCE_DIR}/python/test_param_ranges.py
                   --ignore=${CMAKE_CURRENT_SOURCE_DIR}/python/test_random_machines.py
                   --ignore=${CMAKE_CURRENT_SOURCE_DIR}/python/test_start_polarity.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python/pytest PROPERTIES LABELS python TIMEOUT 900
    ENVIRONMENT "FLUXDRIVE_SIL=$<TARGET_FILE:fluxdrive-sil>")
  # the star-point and Kalman ranges walked at their edges on the star-point
  # presets (issue 22, point 9): on its own, so that -R finds it
  add_test(NAME python/param_ranges
           COMMAND ${FD_PYTHON} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/python/test_param_ranges.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python/param_ranges PROPERTIES LABELS python TIMEOUT 300
    ENVIRONMENT "FLUXDRIVE_SIL=$<TARGET_FILE:fluxdrive-sil>")
  # the acceptance tests on random machines (issue 23, point 19,
  # docs/machines.md): on their own, in parallel with the rest
  add_test(NAME python/random_machines
           COMMAND ${FD_PYTHON} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/python/test_random_machines.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python/random_machines PROPERTIES LABELS python TIMEOUT 300
    ENVIRONMENT "FLUXDRIVE_SIL=$<TARGET_FILE:fluxdrive-sil>")
  # the star-point sources' polarity decision over start angles, noise,
  # sources and presets (issue 23, point 1): a seeded subset, the full grid
  # with FD_POLARITY_FULL=1
  add_test(NAME python/start_polarity
           COMMAND ${FD_PYTHON} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/python/test_start_polarity.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python/start_polarity PROPERTIES LABELS python TIMEOUT 300
    ENVIRONMENT "FLUXDRIVE_SIL=$<TARGET_FILE:fluxdrive-sil>")
  # the parameter table of the firmware against the DBC, the tools' table
  # and docs/parameters.md (fluxdrive params --check)
  add_test(NAME params/agreement
           COMMAND ${FD_PYTHON} -m fluxdrive params --check --sil $<TARGET_FILE:fluxdrive-sil>
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(params/agreement PROPERTIES LABELS python TIMEOUT 120)
else()
  message(STATUS "FD_PYTHON not set: pytest not registered (scripts/test.sh sets it)")
endif()
