# Install-time part of cmake/Install.cmake: writes rdtfd.service and rdtfd.json for the prefix
# being installed into (CMAKE_INSTALL_PREFIX as the install step sees it) and installs them.
# Inputs: RDTF_SOURCE_DIR, RDTF_STAGING_DIR (scratch folder in the build tree), RDTF_BINDIR.

# replace_or_fail(VAR FROM TO): a missed replacement would ship a wrong file silently.
function(rdtf_replace_or_fail var from to)
  string(FIND "${${var}}" "${from}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "packaging: '${from}' not found: update cmake/InstallDaemonFiles.cmake")
  endif()
  string(REPLACE "${from}" "${to}" text "${${var}}")
  set(${var} "${text}" PARENT_SCOPE)
endfunction()

# As GNUInstallDirs: the prefix /usr keeps its configuration in /etc, any other prefix in P/etc.
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  set(sysconfdir /etc)
else()
  set(sysconfdir ${CMAKE_INSTALL_PREFIX}/etc)
endif()
set(config_path ${sysconfdir}/rdtf/rdtfd.json)

file(READ ${RDTF_SOURCE_DIR}/config/rdtfd.service unit)
rdtf_replace_or_fail(unit "/usr/local/bin/rdtfd --config /etc/rdtf/rdtfd.json"
                     "${CMAKE_INSTALL_PREFIX}/${RDTF_BINDIR}/rdtfd --config ${config_path}")
file(READ ${RDTF_SOURCE_DIR}/config/rdtfd.json config)
rdtf_replace_or_fail(config "\"../examples/models\"" "\"/var/lib/rdtf/models\"")
rdtf_replace_or_fail(config "\"../build/rdtf-output\"" "\"/var/lib/rdtf/output\"")

file(WRITE ${RDTF_STAGING_DIR}/rdtfd.service "${unit}")
file(WRITE ${RDTF_STAGING_DIR}/rdtfd.json "${config}")
file(INSTALL DESTINATION ${CMAKE_INSTALL_PREFIX}/lib/systemd/system TYPE FILE
     FILES ${RDTF_STAGING_DIR}/rdtfd.service)
file(INSTALL DESTINATION ${sysconfdir}/rdtf TYPE FILE FILES ${RDTF_STAGING_DIR}/rdtfd.json)
