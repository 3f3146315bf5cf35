# Run after viewcells_tests is built (cmake -P): writes CTEST_FILE with ctest tests that each run
# up to 4 tests of one GoogleTest suite in one process ("Suite", or "Suite/1", "Suite/2", ...
# when a suite has more). One process per test, as gtest_discover_tests makes them, cost the
# suite about 11 s of CPU in process starts over 174 tests; a whole suite per process made the
# Subdivision suite one test of a minute under the sanitizers. A single test runs with
# `tests/viewcells_tests --gtest_filter=Suite.Name`.
# A ctest test all of whose tests skip (the OpenArena maps not fetched) is reported as skipped
# (support/gtest_main.cpp's --all-skipped-exit); one with a failing test fails.
set(per_test 4)
execute_process(COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
                OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE rc TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests failed (${rc}): ${errors}")
endif()
# Suite names in order, and each suite's tests.
string(REPLACE "\n" ";" lines "${listing}")
set(suites "")
foreach(line IN LISTS lines)
  if(line MATCHES "^([A-Za-z_][A-Za-z0-9_]*)\\.")
    set(suite "${CMAKE_MATCH_1}")
    list(APPEND suites "${suite}")
    set(tests_${suite} "")
  elseif(line MATCHES "^  ([A-Za-z_][A-Za-z0-9_]*)" AND DEFINED suite)
    list(APPEND tests_${suite} "${suite}.${CMAKE_MATCH_1}")
  endif()
endforeach()
if(NOT suites)
  message(FATAL_ERROR "${TEST_EXECUTABLE} lists no test suite")
endif()
set(content "")
foreach(suite IN LISTS suites)
  list(LENGTH tests_${suite} n)
  math(EXPR parts "(${n} + ${per_test} - 1) / ${per_test}")
  foreach(part RANGE 1 ${parts})
    math(EXPR first "(${part} - 1) * ${per_test}")
    math(EXPR last "${first} + ${per_test} - 1")
    if(last GREATER_EQUAL n)
      math(EXPR last "${n} - 1")
    endif()
    set(filter "")
    foreach(i RANGE ${first} ${last})
      list(GET tests_${suite} ${i} name)
      list(APPEND filter "${name}")
    endforeach()
    list(JOIN filter ":" filter)
    set(test_name "${suite}")
    if(parts GREATER 1)
      set(test_name "${suite}/${part}")
    endif()
    string(APPEND content
           "add_test([=[${test_name}]=] [=[${TEST_EXECUTABLE}]=] [=[--gtest_filter=${filter}]=] --all-skipped-exit=77)\n"
           "set_tests_properties([=[${test_name}]=] PROPERTIES WORKING_DIRECTORY [=[${WORKING_DIRECTORY}]=] "
           "SKIP_RETURN_CODE 77)\n")
  endforeach()
endforeach()
file(WRITE "${CTEST_FILE}" "${content}")
