# `make install` (cmake --install, PREFIX and DESTDIR) and the Debian package (`make package`,
# CPack): the daemon and the command line, the client libraries with sonames, their headers and
# pkg-config files, the systemd units, sysusers and tmpfiles files, the default configuration in
# /etc/canemu, the documentation and the Python package. docs/security.md, "Installing".
include(GNUInstallDirs)

# The package's maintainer: a distributor sets their own (-DCANEMU_PACKAGE_CONTACT=...).
set(CANEMU_PACKAGE_CONTACT "canemu maintainers <canemu@localhost>"
    CACHE STRING "Maintainer of the Debian package (name <address>)")


set(CANEMU_INSTALLED_LIBRARIES vcinpl vcinpl2 vciapi xcan sl64)
foreach(lib ${CANEMU_INSTALLED_LIBRARIES})
  set_target_properties(${lib} PROPERTIES VERSION ${PROJECT_VERSION} SOVERSION ${PROJECT_VERSION_MAJOR})
endforeach()
install(TARGETS canemud canemu RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS ${CANEMU_INSTALLED_LIBRARIES} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})

# The headers as a program includes them: <vci/vcinpl.h>'s directory holds every VCI header,
# <sorcus/xcan.h>'s both SORCUS ones (the build gathers them the same way).
install(DIRECTORY ${PROJECT_BINARY_DIR}/include/vci ${PROJECT_BINARY_DIR}/include/sorcus
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# pkg-config files for the installed tree, relocatable (prefix found from the file's own place).
set(pc_dir ${PROJECT_BINARY_DIR}/install-pkgconfig)
file(RELATIVE_PATH pc_up /root/${CMAKE_INSTALL_LIBDIR}/pkgconfig /root)
string(REGEX REPLACE "/$" "" pc_up "${pc_up}")
string(CONCAT pc_head "prefix=\${pcfiledir}/${pc_up}\n"
       "includedir=\${prefix}/${CMAKE_INSTALL_INCLUDEDIR}\n"
       "libdir=\${prefix}/${CMAKE_INSTALL_LIBDIR}\n\n")
file(WRITE ${pc_dir}/canemu-vci.pc "${pc_head}Name: canemu-vci\n"
     "Description: IXXAT VCI headers of canemu, the CAN adapter emulator\n"
     "Version: ${PROJECT_VERSION}\nCflags: -I\${includedir}/vci\nLibs: -L\${libdir}\n")
file(WRITE ${pc_dir}/canemu-xcan.pc "${pc_head}Name: canemu-xcan\n"
     "Description: SORCUS X-CAN-2i channel library of canemu, the CAN adapter emulator\n"
     "Version: ${PROJECT_VERSION}\nCflags: -I\${includedir}/sorcus\nLibs: -L\${libdir} -lxcan\n")
file(WRITE ${pc_dir}/canemu-sl64.pc "${pc_head}Name: canemu-sl64\n"
     "Description: SORCUS SL-CANi library (SL64_LIB) of canemu, the CAN adapter emulator\n"
     "Version: ${PROJECT_VERSION}\nCflags: -I\${includedir}/sorcus\nLibs: -L\${libdir} -lsl64\n")
set(pc_files ${pc_dir}/canemu-vci.pc ${pc_dir}/canemu-xcan.pc ${pc_dir}/canemu-sl64.pc)
foreach(lib vciapi vcinpl vcinpl2)
  file(WRITE ${pc_dir}/canemu-${lib}.pc "${pc_head}Name: canemu-${lib}\n"
       "Description: IXXAT VCI library lib${lib} of canemu, the CAN adapter emulator\n"
       "Version: ${PROJECT_VERSION}\nRequires: canemu-vci = ${PROJECT_VERSION}\n"
       "Libs: -L\${libdir} -l${lib}\n")
  list(APPEND pc_files ${pc_dir}/canemu-${lib}.pc)
endforeach()
install(FILES ${pc_files} DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# The VCI .NET assembly (docs/dotnet.md) where Debian puts CLI libraries, with its dllmap, and a
# pkg-config file for the compiler: mcs app.cs $(pkg-config --libs canemu-vcinet2).
if(TARGET vcinet2)
  set(CANEMU_CLI_DIR lib/cli/canemu)
  install(FILES ${PROJECT_BINARY_DIR}/lib/vcinet2.dll ${PROJECT_BINARY_DIR}/lib/vcinet2.dll.config
          DESTINATION ${CANEMU_CLI_DIR})
  file(WRITE ${pc_dir}/canemu-vcinet2.pc "prefix=\${pcfiledir}/${pc_up}\n"
       "assemblydir=\${prefix}/${CANEMU_CLI_DIR}\n\nName: canemu-vcinet2\n"
       "Description: IXXAT VCI .NET API (Ixxat.Vci3) of canemu, the CAN adapter emulator\n"
       "Version: ${PROJECT_VERSION}\nLibs: -r:\${assemblydir}/vcinet2.dll\n")
  install(FILES ${pc_dir}/canemu-vcinet2.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
endif()

# systemd units, sysusers and tmpfiles under the prefix's lib/ (what systemd reads for /usr);
# the configuration in /etc/canemu for the prefix /usr, else PREFIX/etc/canemu. Decided when
# installing, so `cmake --install --prefix` and CPack (/usr) both get paths that hold.
install(FILES ${PROJECT_SOURCE_DIR}/systemd/canemud.socket DESTINATION lib/systemd/system)
install(FILES ${PROJECT_SOURCE_DIR}/systemd/canemu.sysusers DESTINATION lib/sysusers.d
        RENAME canemu.conf)
install(FILES ${PROJECT_SOURCE_DIR}/systemd/canemu.tmpfiles DESTINATION lib/tmpfiles.d
        RENAME canemu.conf)
# The drop-ins that open the bridges' address families to canemud.service, and the one that lets
# it hold simulation.cpu_latency_us's request (not active until an administrator links them into
# /etc/systemd/system/canemud.service.d/: docs/security.md).
install(FILES ${PROJECT_SOURCE_DIR}/systemd/canemud.service.d/socketcan.conf
              ${PROJECT_SOURCE_DIR}/systemd/canemud.service.d/ip.conf
              ${PROJECT_SOURCE_DIR}/systemd/canemud.service.d/cpu-latency.conf
        DESTINATION ${CMAKE_INSTALL_DATADIR}/canemu/systemd)
install(CODE "set(CANEMU_SOURCE_DIR \"${PROJECT_SOURCE_DIR}\")
              set(CANEMU_STAGE \"${PROJECT_BINARY_DIR}/install-systemd\")
              set(CANEMU_BINDIR \"${CMAKE_INSTALL_BINDIR}\")")
install(CODE [[
  if(CMAKE_INSTALL_PREFIX STREQUAL "/usr")
    set(etc "/etc")
  else()
    set(etc "${CMAKE_INSTALL_PREFIX}/etc")
  endif()
  file(READ "${CANEMU_SOURCE_DIR}/systemd/canemud.service" unit)
  string(REPLACE "/usr/bin/canemud" "${CMAKE_INSTALL_PREFIX}/${CANEMU_BINDIR}/canemud" unit
         "${unit}")
  string(REPLACE "/etc/canemu/" "${etc}/canemu/" unit "${unit}")
  file(WRITE "${CANEMU_STAGE}/canemud.service" "${unit}")
  file(INSTALL "${CANEMU_STAGE}/canemud.service"
       DESTINATION "${CMAKE_INSTALL_PREFIX}/lib/systemd/system")
  # The configuration is the administrator's once it is there: installed only where none is
  # (as the package's conffile is kept on upgrade), never overwritten by a second install.
  if(EXISTS "$ENV{DESTDIR}${etc}/canemu/canemud.toml")
    message(STATUS "Kept: $ENV{DESTDIR}${etc}/canemu/canemud.toml (the default is "
                   "${CANEMU_SOURCE_DIR}/config/default.toml)")
  else()
    file(INSTALL "${CANEMU_SOURCE_DIR}/config/default.toml" DESTINATION "${etc}/canemu"
         RENAME canemud.toml)
  endif()
]])
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/examples ${PROJECT_SOURCE_DIR}/config/faults
        DESTINATION ${CMAKE_INSTALL_DATADIR}/canemu)

install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/packaging/debian/copyright
        DESTINATION ${CMAKE_INSTALL_DOCDIR})
# A native package's changelog, compressed as Debian wants it (gzip -9n: no name, no time).
string(TIMESTAMP changelog_date "%a, %d %b %Y %H:%M:%S +0000" UTC)
file(WRITE ${PROJECT_BINARY_DIR}/install-doc/changelog
     "canemu (${PROJECT_VERSION}) unstable; urgency=medium\n\n"
     "  * Built from the canemu source tree; docs/ describes this version.\n\n"
     " -- ${CANEMU_PACKAGE_CONTACT}  ${changelog_date}\n")
execute_process(COMMAND gzip -9nf ${PROJECT_BINARY_DIR}/install-doc/changelog)
install(FILES ${PROJECT_BINARY_DIR}/install-doc/changelog.gz DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}
        FILES_MATCHING PATTERN "*.md" PATTERN examples EXCLUDE)
# What lintian reports of the package and is accepted, each with its reason
# (tests/install/check_lintian.sh fails on any other tag).
install(FILES ${PROJECT_SOURCE_DIR}/packaging/debian/lintian-overrides
        DESTINATION ${CMAKE_INSTALL_DATADIR}/lintian/overrides RENAME canemu)

# The Python package where Debian's python3 finds it, with the entry points that make
# can.Bus(interface="canemu") work and bring the pytest plugin (docs/testing.md).
set(CANEMU_PYTHON_DIR lib/python3/dist-packages)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/client/python/canemu DESTINATION ${CANEMU_PYTHON_DIR}
        FILES_MATCHING PATTERN "*.py" PATTERN "web_static/*" PATTERN "__pycache__" EXCLUDE)
# send()'s hot path in C, beside the package (import canemu_speedups), when it was built.
if(TARGET canemu_speedups)
  install(TARGETS canemu_speedups LIBRARY DESTINATION ${CANEMU_PYTHON_DIR})
endif()
# The LCM bridge's message types (docs/bridges.md): Python beside canemu, the C++ headers lcm-gen
# made (<canemu_lcm/frame_t.hpp>) and the .lcm files for other languages' lcm-gen.
install(DIRECTORY ${PROJECT_SOURCE_DIR}/client/python/canemu_lcm DESTINATION ${CANEMU_PYTHON_DIR}
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
if(CANEMU_LCM)
  install(DIRECTORY ${PROJECT_BINARY_DIR}/include/canemu_lcm DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endif()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/daemon/src/bridges/lcm_types/canemu_lcm DESTINATION ${CMAKE_INSTALL_DATADIR}/canemu/lcm
        FILES_MATCHING PATTERN "*.lcm")
set(dist_info ${PROJECT_BINARY_DIR}/install-python/canemu-${PROJECT_VERSION}.dist-info)
file(WRITE ${dist_info}/METADATA
     "Metadata-Version: 2.1\nName: canemu\nVersion: ${PROJECT_VERSION}\n"
     "Summary: python-can interface and tools of canemu, the CAN/LIN adapter emulator\n"
     "Requires-Dist: python-can>=4.1\n")
file(WRITE ${dist_info}/entry_points.txt
     "[can.interface]\ncanemu = canemu.bus:CanemuBus\n\n[pytest11]\ncanemu = canemu.pytest_plugin\n")
file(WRITE ${dist_info}/INSTALLER "canemu\n")
file(WRITE ${dist_info}/top_level.txt "canemu\n")
install(DIRECTORY ${dist_info} DESTINATION ${CANEMU_PYTHON_DIR})

# ---- CPack: a Debian package ----
set(CPACK_PACKAGE_NAME canemu)
set(CPACK_PACKAGE_VENDOR "canemu")
set(CPACK_PACKAGE_CONTACT "${CANEMU_PACKAGE_CONTACT}")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "emulated IXXAT and SORCUS CAN/LIN adapters")
# One string: set() with several would make a list, whose ";" separators begin the Description's
# continuation lines (CPack puts the text after the summary, each line indented by one space).
string(CONCAT CPACK_PACKAGE_DESCRIPTION
       "canemud emulates IXXAT (VCI) and SORCUS CAN and LIN interface adapters\n"
       "down to the controller silicon, in real time; programs written for them\n"
       "link canemu's client libraries and run without hardware.")
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION misc)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# shlibs and the ldconfig trigger for the five libraries; binaries and libraries stripped.
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS ON)
set(CPACK_DEBIAN_PACKAGE_GENERATE_SHLIBS_POLICY ">=")
set(CPACK_STRIP_FILES ON)
# init-system-helpers: deb-systemd-helper and deb-systemd-invoke in the maintainer scripts.
set(CPACK_DEBIAN_PACKAGE_DEPENDS "systemd, init-system-helpers (>= 1.54~), python3, python3-can")
# canemu plot; canemu web (docs/web.md)
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "python3-matplotlib, python3-aiohttp, libjs-chart.js")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "mono-runtime")  # the VCI .NET assembly (/usr/lib/cli/canemu)
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA
    ${PROJECT_SOURCE_DIR}/packaging/debian/conffiles ${PROJECT_SOURCE_DIR}/packaging/debian/postinst
    ${PROJECT_SOURCE_DIR}/packaging/debian/prerm ${PROJECT_SOURCE_DIR}/packaging/debian/postrm
    ${PROJECT_SOURCE_DIR}/packaging/debian/triggers)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
include(CPack)
# The DDS bridge's types (docs/bridges.md): the IDL files for any DDS implementation's IDL
# compiler, and the Python types beside canemu.
install(FILES ${PROJECT_SOURCE_DIR}/daemon/src/bridges/dds_types/canemu_dds.idl ${PROJECT_SOURCE_DIR}/daemon/src/bridges/dds_types/ros2_can_msgs.idl
        DESTINATION ${CMAKE_INSTALL_DATADIR}/canemu/idl)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/client/python/canemu_dds DESTINATION ${CANEMU_PYTHON_DIR}
        FILES_MATCHING PATTERN "*.py" PATTERN "__pycache__" EXCLUDE)
