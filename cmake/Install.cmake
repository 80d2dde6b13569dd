# Install rules beyond each target's own, and the Debian package (cpack -G DEB).
# Components: dev (librdtf, headers, CMake package config), daemon (rdtfd, unit, config),
# clients (rdtf, rdtf-echo, rdtf-pd-controller, rdtf-spy and the LCM types jar).
include(CMakePackageConfigHelpers)

# --- find_package(rdtf) -----------------------------------------------------------------------
set(RDTF_CMAKE_INSTALL_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/rdtf)
install(EXPORT rdtfTargets NAMESPACE rdtf:: DESTINATION ${RDTF_CMAKE_INSTALL_DIR} COMPONENT dev)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rdtfConfig.cmake.in
  ${PROJECT_BINARY_DIR}/packaging/rdtfConfig.cmake INSTALL_DESTINATION ${RDTF_CMAKE_INSTALL_DIR})
# 0.x: a minor version may change the API, so only the same minor version is compatible.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/packaging/rdtfConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/packaging/rdtfConfig.cmake
              ${PROJECT_BINARY_DIR}/packaging/rdtfConfigVersion.cmake
        DESTINATION ${RDTF_CMAKE_INSTALL_DIR} COMPONENT dev)

if(RDTF_CORE_ONLY)
  return()
endif()

# --- daemon: systemd unit and config ------------------------------------------------------------
# config/ holds the files for a source checkout (rdtfd.service runs /usr/local/bin/rdtfd; rdtfd.json
# watches examples/models). The installed copies name the installed binary and config, and keep
# models and output under the unit's state directory, /var/lib/rdtf. They are written at install
# time (cmake/InstallDaemonFiles.cmake), since only then is the prefix known: cpack installs into
# /usr (config in /etc), `cmake --install --prefix P` into P (config in P/etc).
install(CODE "
  set(RDTF_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")
  set(RDTF_STAGING_DIR \"${PROJECT_BINARY_DIR}/packaging/daemon-files\")
  set(RDTF_BINDIR \"${CMAKE_INSTALL_BINDIR}\")
  include(\"${PROJECT_SOURCE_DIR}/cmake/InstallDaemonFiles.cmake\")" COMPONENT daemon)

# --- clients: lcm-spy launcher and the LCM types jar it loads -----------------------------------
install(PROGRAMS ${PROJECT_SOURCE_DIR}/scripts/rdtf-spy DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT clients)
if(RDTF_LCM_JAR)
  install(FILES ${RDTF_LCM_JAR} DESTINATION ${CMAKE_INSTALL_DATADIR}/rdtf/java COMPONENT clients)
endif()

# --- cpack -G DEB: one package with everything above ------------------------------------------
set(CPACK_PACKAGE_NAME rdtf)
set(CPACK_PACKAGE_VENDOR "rdtf")
set(CPACK_PACKAGE_CONTACT "rdtf maintainers <rdtf@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "glTF 2.0 to RDTF robot descriptions: rdtfd daemon, command line clients and librdtf")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_PACKAGE_DIRECTORY ${PROJECT_BINARY_DIR}/packages)
set(CPACK_DEB_COMPONENT_INSTALL OFF)
# Binaries without their debug information (a RelWithDebInfo build's would make it 350 MB).
set(CPACK_STRIP_FILES ON)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
# Shared-library dependencies from dpkg-shlibdeps (dpkg-dev); the rest by hand: lcm-spy and its
# Java pieces for rdtf-spy, the -dev packages for find_package(rdtf).
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_DEPENDS "adduser")  # postinst makes the system user rdtf
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "liblcm-bin, liblcm-java, default-jre | java-runtime, libjchart2d-java")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "libeigen3-dev, nlohmann-json3-dev, libtinygltf-dev, cmake")
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/packaging/debian/conffiles ${PROJECT_SOURCE_DIR}/packaging/debian/postinst)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
