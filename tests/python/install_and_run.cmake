# ctest driver of the Python tests: installs the project (the texwarp package and what it links) into a fresh prefix,
# then runs a test script with /usr/bin/python3 and PYTHONPATH at that prefix's site-packages only.
# -DBUILD_DIR= -DPREFIX= -DPYTHON= -DSITE= (relative to PREFIX) -DSCRIPT= -DTEXWARPD= -DTEXWARP_CLI= -DSOURCE_DIR=
file(REMOVE_RECURSE "${PREFIX}")
execute_process(COMMAND "${CMAKE_COMMAND}" --install "${BUILD_DIR}" --prefix "${PREFIX}" OUTPUT_QUIET
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "cmake --install failed (${rc})")
endif()
set(ENV{PYTHONPATH} "${PREFIX}/${SITE}")
set(ENV{TEXWARP_PREFIX} "${PREFIX}")
set(ENV{TEXWARPD} "${TEXWARPD}")
set(ENV{TEXWARP_CLI} "${TEXWARP_CLI}")
set(ENV{TEXWARP_SOURCE_DIR} "${SOURCE_DIR}")
set(ENV{POCL_CACHE_DIR} "${BUILD_DIR}/pocl-cache")
execute_process(COMMAND "${PYTHON}" -s "${SCRIPT}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${SCRIPT} failed (${rc})")
endif()
