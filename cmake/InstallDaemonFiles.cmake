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
rdtf_replace_or_fail(unit "# systemd unit for rdtfd from a source checkout. Install: copy to /etc/systemd/system/, put the
# config in /etc/rdtf/rdtfd.json (watch and output folders as absolute paths), then
#   systemctl daemon-reload && systemctl enable --now rdtfd"
                     "# systemd unit for rdtfd, as installed. Edit ${config_path} (watch and output folders as
# absolute paths), then
#   systemctl enable --now rdtfd")
# The package (prefix /usr) runs rdtfd as the system user rdtf that its postinst makes
# (packaging/debian/postinst); an install elsewhere has no such user and runs it as root, confined.
if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
  rdtf_replace_or_fail(unit "#User=\n" "User=rdtf\nGroup=rdtf\n")
  rdtf_replace_or_fail(unit "# The package runs it as the system user rdtf (its postinst makes it); here it is root, confined
# below." "# It runs as the system user rdtf (the package's postinst makes it), confined below.")
endif()
file(READ ${RDTF_SOURCE_DIR}/config/rdtfd.json config)
rdtf_replace_or_fail(config "\"../examples/models\"" "\"/var/lib/rdtf/models\"")
rdtf_replace_or_fail(config "\"../build/rdtf-output\"" "\"/var/lib/rdtf/output\"")
rdtf_replace_or_fail(config "(except watch and output, set here for scripts/run.sh)"
                     "(except watch and output, kept under /var/lib/rdtf, the state directory of the unit)")

file(WRITE ${RDTF_STAGING_DIR}/rdtfd.service "${unit}")
file(WRITE ${RDTF_STAGING_DIR}/rdtfd.json "${config}")
file(INSTALL DESTINATION ${CMAKE_INSTALL_PREFIX}/lib/systemd/system TYPE FILE
     FILES ${RDTF_STAGING_DIR}/rdtfd.service)
file(INSTALL DESTINATION ${sysconfdir}/rdtf TYPE FILE FILES ${RDTF_STAGING_DIR}/rdtfd.json)
