# Writes mpath_version.h with the current git commit; run at every build so
# that reports and images name the commit the binaries were built from.
execute_process(COMMAND git rev-parse --short HEAD
  WORKING_DIRECTORY ${SOURCE_DIR}
  OUTPUT_VARIABLE MPATH_GIT_COMMIT OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
execute_process(COMMAND git status --porcelain --untracked-files=no
  WORKING_DIRECTORY ${SOURCE_DIR}
  OUTPUT_VARIABLE MPATH_GIT_DIRTY OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
if(NOT MPATH_GIT_COMMIT)
  set(MPATH_GIT_COMMIT "unknown")
elseif(MPATH_GIT_DIRTY)
  set(MPATH_GIT_COMMIT "${MPATH_GIT_COMMIT}+changes")
endif()
configure_file(${SOURCE_DIR}/src/util/version.h.in ${OUTPUT} @ONLY)
