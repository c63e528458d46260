# Run at every build (cmake -P, by cmake/build_info/CMakeLists.txt): writes OUTPUT from TEMPLATE with
# TEXWARP_COMMIT = `git rev-parse --short HEAD` of SOURCE_DIR, or "unknown" when SOURCE_DIR is no git checkout (a
# tarball) or git is missing. configure_file leaves OUTPUT untouched when its text is the same, so nothing rebuilds.
set(TEXWARP_COMMIT unknown)
if(EXISTS "${SOURCE_DIR}/.git" AND GIT_EXECUTABLE)
  execute_process(COMMAND "${GIT_EXECUTABLE}" -C "${SOURCE_DIR}" rev-parse --short HEAD
    OUTPUT_VARIABLE commit RESULT_VARIABLE result OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
  if(result EQUAL 0 AND commit MATCHES "^[0-9a-f]+$")
    set(TEXWARP_COMMIT "${commit}")
  endif()
endif()
configure_file("${TEMPLATE}" "${OUTPUT}" @ONLY)
