# rdtf_check_patched_source(DIR NAME PACKAGE PROBE REASON): stops the configure unless DIR holds
# Debian's source of NAME with exactly scripts/NAME/*.patch applied, for the installed version of
# PACKAGE, as scripts/install-deps.sh leaves it (its .rdtf-patched stamp: the SHA-256 of that
# version and the patches' texts). PROBE is a file DIR must hold; REASON says why the patches matter.
function(rdtf_check_patched_source dir name package probe reason)
  if(NOT EXISTS ${dir}/.rdtf-patched OR NOT EXISTS ${dir}/${probe})
    message(FATAL_ERROR "no patched ${name} source in ${dir}: run scripts/install-deps.sh (or set the cache "
                        "variable that names the folder); ${reason}")
  endif()
  file(READ ${dir}/.rdtf-patched stamp)
  string(STRIP "${stamp}" stamp)
  file(GLOB patches ${PROJECT_SOURCE_DIR}/scripts/${name}/*.patch)
  execute_process(COMMAND dpkg-query -W -f=\${Version} ${package} OUTPUT_VARIABLE version ERROR_QUIET)
  set(expected "${version}\n")
  foreach(patch_file ${patches})
    file(READ ${patch_file} patch_text)
    string(APPEND expected "${patch_text}")
  endforeach()
  string(SHA256 expected "${expected}")
  if(NOT stamp STREQUAL expected)
    message(FATAL_ERROR "${dir} was patched with other patches than scripts/${name}/*.patch or for another "
                        "${package} version: run scripts/install-deps.sh again")
  endif()
  # A new or changed patch configures again (and so stops here until install-deps has run).
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${patches} ${dir}/.rdtf-patched)
endfunction()
