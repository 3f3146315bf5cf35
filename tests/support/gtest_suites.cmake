# Run after viewcells_tests is built (cmake -P): writes CTEST_FILE with one ctest test per
# GoogleTest suite of TEST_EXECUTABLE, running that suite's tests in one process. One process
# per test, as gtest_discover_tests makes them, cost the suite about 11 s of CPU in process
# starts over 174 tests. A single test runs with `tests/viewcells_tests --gtest_filter=Suite.Name`.
# A suite all of whose tests skip (the OpenArena maps not fetched) is reported as skipped
# (support/gtest_main.cpp's --all-skipped-exit); one with a failing test fails.
execute_process(COMMAND "${TEST_EXECUTABLE}" --gtest_list_tests
                OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE rc TIMEOUT 60)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} --gtest_list_tests failed (${rc}): ${errors}")
endif()
string(REPLACE "\n" ";" lines "${listing}")
set(content "")
set(count 0)
foreach(line IN LISTS lines)
  if(line MATCHES "^([A-Za-z_][A-Za-z0-9_]*)\\.")
    set(suite "${CMAKE_MATCH_1}")
    string(APPEND content
           "add_test([=[${suite}]=] [=[${TEST_EXECUTABLE}]=] [=[--gtest_filter=${suite}.*]=] --all-skipped-exit=77)\n"
           "set_tests_properties([=[${suite}]=] PROPERTIES WORKING_DIRECTORY [=[${WORKING_DIRECTORY}]=] "
           "SKIP_RETURN_CODE 77)\n")
    math(EXPR count "${count} + 1")
  endif()
endforeach()
if(count EQUAL 0)
  message(FATAL_ERROR "${TEST_EXECUTABLE} lists no test suite")
endif()
file(WRITE "${CTEST_FILE}" "${content}")
