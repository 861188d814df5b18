# Registers one CTest test per GoogleTest suite of EXECUTABLE (run after each
# build of it): a suite's tests share their fixtures (tables, GL context,
# SetUpTestSuite), so they run in one process. Writes OUTPUT, a CTest script.
#   -DEXECUTABLE=... -DOUTPUT=... -DPREFIX=... (test name prefix, may be empty)
#   -DLABELS=label;... (for every suite) -DFULL_ONLY="regex of full-tier-only suites"
#   -DGPU_SUITES="regex of the suites that compile shaders" (label gpu)
#   -DAPP_SUITES="regex of the suites that run the CLI or the example" (label apps)
#   -DSKIP_APP_SUITES=1 (those suites are not registered: their programs are not built)
#   -DSLOW_SUITES="regex of the unit suites slow under the sanitizers" (label slow)
#   -DTIMES=<file of "suite seconds" lines> -DTIMEOUT=seconds -DENVIRONMENT="VAR=value;..."
#   -DGPU_ENVIRONMENT="VAR=value;..." (added for the gpu and apps suites but
#    those of -DDRAW_BOUND_SUITES="regex")
execute_process(COMMAND ${EXECUTABLE} --gtest_list_tests OUTPUT_VARIABLE listing RESULT_VARIABLE result
                ERROR_VARIABLE errors)
if(NOT result EQUAL 0)
  message(FATAL_ERROR "${EXECUTABLE} --gtest_list_tests failed (${result}): ${errors}")
endif()

# Measured seconds per suite (tests/test_times.txt, written by
# scripts/slowest_tests.py --write-times): the speed labels follow them.
set(known_times "")
if(EXISTS ${TIMES})
  file(STRINGS ${TIMES} time_lines REGEX "^[^#]")
  foreach(line IN LISTS time_lines)
    string(REGEX MATCH "^([^ ]+) +([0-9.]+)" _ "${line}")
    set(time_${CMAKE_MATCH_1} ${CMAKE_MATCH_2})
  endforeach()
endif()

string(REPLACE "\n" ";" lines "${listing}")
set(script "")
foreach(line IN LISTS lines)
  # Suite lines end with '.', test lines are indented.
  if(line MATCHES "^([^ #][^ ]*)\\.( .*)?$")
    set(suite ${CMAKE_MATCH_1})
    if(APP_SUITES AND suite MATCHES "${APP_SUITES}" AND SKIP_APP_SUITES)
      continue()
    endif()
    set(labels ${LABELS})
    if(FULL_ONLY AND suite MATCHES "${FULL_ONLY}")
      list(APPEND labels full)
    else()
      list(APPEND labels default full)
    endif()
    if(GPU_SUITES AND suite MATCHES "${GPU_SUITES}")
      list(APPEND labels gpu)
    endif()
    if(APP_SUITES AND suite MATCHES "${APP_SUITES}")
      list(APPEND labels apps)
    endif()
    if(SLOW_SUITES AND suite MATCHES "${SLOW_SUITES}")
      list(APPEND labels slow)
    endif()
    string(REPLACE "/" "_" key ${suite})
    unset(seconds)
    if(DEFINED time_${PREFIX}${key})
      set(seconds ${time_${PREFIX}${key}})
      if(seconds LESS 10)
        list(APPEND labels quick)
      elseif(seconds LESS 60)
        list(APPEND labels moderate)
      else()
        list(APPEND labels long)
      endif()
    else()
      list(APPEND labels unmeasured)
    endif()
    # COST: CTest starts the slowest tests first, so that a long suite does
    # not run alone at the end of a parallel run.
    set(cost "")
    if(DEFINED seconds)
      set(cost " COST ${seconds}")
    endif()
    set(environment ${ENVIRONMENT})
    if(((GPU_SUITES AND suite MATCHES "${GPU_SUITES}") OR (APP_SUITES AND suite MATCHES "${APP_SUITES}"))
       AND NOT (DRAW_BOUND_SUITES AND suite MATCHES "${DRAW_BOUND_SUITES}"))
      list(APPEND environment ${GPU_ENVIRONMENT})
    endif()
    string(REPLACE ";" "\\;" environment_arg "${environment}")
    string(APPEND script
      "add_test(\"${PREFIX}${key}\" \"${EXECUTABLE}\" \"--gtest_filter=${suite}.*\" \"--gtest_brief=1\")\n"
      "set_tests_properties(\"${PREFIX}${key}\" PROPERTIES LABELS \"${labels}\" TIMEOUT ${TIMEOUT}${cost}"
      " ENVIRONMENT \"${environment_arg}\")\n")
  endif()
endforeach()
file(WRITE ${OUTPUT} "${script}")
