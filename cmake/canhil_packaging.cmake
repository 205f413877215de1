# canhil as a Debian package (`cpack -G DEB` in a build folder, or the
# `package` target): canhil_VERSION_amd64.deb with the programs, the
# libraries and preloads, the DBC, the layouts, the scenarios and their
# example tests, the viewer's page, the docs and a man page per program,
# installed under /usr. Its dependencies come from the shared libraries the
# programs link (dpkg-shlibdeps); can-utils is recommended (candump beside a
# run), nothing else is needed at run time. tests/install/deb_test.sh builds,
# unpacks and runs it.
include(GNUInstallDirs)
install(FILES ${PROJECT_SOURCE_DIR}/docs/man/canhil.1 ${PROJECT_SOURCE_DIR}/docs/man/canhil-hwcomm.1
              ${PROJECT_SOURCE_DIR}/docs/man/canhil-agent.1 ${PROJECT_SOURCE_DIR}/docs/man/canhil-rtdb-gen.1
        DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR} PATTERN man EXCLUDE)
install(FILES ${PROJECT_SOURCE_DIR}/README.md DESTINATION ${CMAKE_INSTALL_DOCDIR})

set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME canhil)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "canhil")
set(CPACK_PACKAGE_CONTACT "canhil developers <canhil@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "hardware-in-the-loop emulator of a RoboCup MSL robot below its laptop")
set(CPACK_PACKAGE_DESCRIPTION
    "canhil replaces everything below a CAMBADA-design robot's laptop (the FTT-CAN nodes, the robot, the ball and
the field, the camera) so that a team's own handler, RTDB, PMan and agent run unchanged against it, on
SocketCAN or canhil's own user-space bus; canhil test judges a team's regression tests, with JUnit XML.")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)  # canhil_0.1.0_amd64.deb
set(CPACK_DEBIAN_PACKAGE_SECTION electronics)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "can-utils")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "chromium")
# Only what canhil installs; the tests' and benchmarks' programs are not installed.
set(CPACK_STRIP_FILES ON)
include(CPack)
