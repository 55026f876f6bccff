# pytest (tools package) with the venv from scripts/setup.sh; the SIL test
# uses this build's fluxdrive-sil.
set(FD_PYTHON "" CACHE FILEPATH "Python of the tools venv (scripts/setup.sh)")
if(FD_PYTHON)
  # tests that run on their own (in parallel with the rest, found by -R),
  # left out of python/pytest
  set(alone param_ranges random_machines start_polarity ekf_range rls_convergence held_start)
  set(ignore "")
  foreach(name ${alone})
    list(APPEND ignore --ignore=${CMAKE_CURRENT_SOURCE_DIR}/python/test_${name}.py)
  endforeach()
  add_test(NAME python/pytest
           COMMAND ${FD_PYTHON} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/python ${ignore}
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(python/pytest PROPERTIES LABELS python TIMEOUT 900
    ENVIRONMENT "FLUXDRIVE_SIL=$<TARGET_FILE:fluxdrive-sil>")
  # param_ranges: the star-point and Kalman ranges walked at their edges on
  # the star-point presets (issue 22, point 9); random_machines: the
  # acceptance tests on random machines (issue 23, point 19,
  # docs/machines.md); start_polarity: the star-point sources' polarity
  # decision over start angles, noise, sources and presets (issue 23,
  # point 1: a seeded subset, the full grid with FD_POLARITY_FULL=1);
  # ekf_range: the ekf over the range of p it accepts, refused beyond
  # (issue 23, point 4); rls_convergence: the RLS of a, b from +-50 %
  # starts on the star-point presets and drawn machines (issue 23, point 5;
  # FLUXDRIVE_RLS_SEEDS, FLUXDRIVE_RLS_FULL); held_start: the held start against
  # an active load and the encoder's alignment on a light free rotor
  # (issue 23, points 3 and 18)
  foreach(name ${alone})
    add_test(NAME python/${name}
             COMMAND ${FD_PYTHON} -m pytest -q ${CMAKE_CURRENT_SOURCE_DIR}/python/test_${name}.py
             WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
    set_tests_properties(python/${name} PROPERTIES LABELS python TIMEOUT 300
      ENVIRONMENT "FLUXDRIVE_SIL=$<TARGET_FILE:fluxdrive-sil>")
  endforeach()
  # the parameter table of the firmware against the DBC, the tools' table
  # and docs/parameters.md (fluxdrive params --check)
  add_test(NAME params/agreement
           COMMAND ${FD_PYTHON} -m fluxdrive params --check --sil $<TARGET_FILE:fluxdrive-sil>
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(params/agreement PROPERTIES LABELS python TIMEOUT 120)
  # the signal tables against docs/log-format.md, the DBC's signal comments,
  # the tools' signal table and the PIL field list (fluxdrive signals --check)
  add_test(NAME signals/agreement
           COMMAND ${FD_PYTHON} -m fluxdrive signals --check --sil $<TARGET_FILE:fluxdrive-sil>
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(signals/agreement PROPERTIES LABELS python TIMEOUT 120)
else()
  message(STATUS "FD_PYTHON not set: pytest not registered (scripts/test.sh sets it)")
endif()
