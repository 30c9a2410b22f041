# Writes OUT, a CTest file with one test per GoogleTest suite of TEST_EXE (run from WORKDIR with
# --gtest_filter=<suite>.*), from the binary's own --gtest_list_tests. Run after every link of
# the test binary (tests/CMakeLists.txt); CTest reads OUT through TEST_INCLUDE_FILES.
execute_process(COMMAND "${TEST_EXE}" --gtest_list_tests
                WORKING_DIRECTORY "${WORKDIR}"
                OUTPUT_VARIABLE listing
                RESULT_VARIABLE status
                TIMEOUT 120)
if(NOT status EQUAL 0)
    message(FATAL_ERROR "${TEST_EXE} --gtest_list_tests failed: ${status}")
endif()
# Parameter values in the listing may hold semicolons, CMake's list separator.
string(REPLACE ";" "," listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(content "")
set(suites 0)
foreach(line IN LISTS lines)
    # A suite line starts in the first column: "Name." or "Prefix/Name.  # TypeParam = ...";
    # its tests follow, indented.
    if(line MATCHES "^([^ #][^ ]*)\\.")
        set(suite "${CMAKE_MATCH_1}")
        string(APPEND content
               "add_test([=[${suite}]=] [==[${TEST_EXE}]==] [==[--gtest_filter=${suite}.*]==])\n"
               "set_tests_properties([=[${suite}]=] PROPERTIES WORKING_DIRECTORY [==[${WORKDIR}]==]"
               " TIMEOUT ${TIMEOUT})\n")
        math(EXPR suites "${suites} + 1")
    endif()
endforeach()
if(suites EQUAL 0)
    message(FATAL_ERROR "${TEST_EXE} --gtest_list_tests listed no test suite")
endif()
file(WRITE "${OUT}" "${content}")
