# `cmake --install` of deploy/'s files, component `service` (included by
# server/robodiffd/CMakeLists.txt: they are robodiffd's). Under the install prefix:
#   etc/robodiff/             robodiffd.conf, roudi.toml, cyclonedds.xml (the loopback file);
#                             one already there and edited is kept (a reinstall keeps an
#                             operator's settings); /etc/robodiff when the prefix is /usr
#   share/robodiff/deploy/    the files as shipped, cyclonedds-lan.xml included
#   lib/systemd/system/       robodiffd.service and iox-roudi.service, their paths rewritten
#                             for the prefix given at install time (install_service_files.cmake)
#   lib/sysusers.d/robodiff.conf   the service user (deploy/systemd/robodiff.sysusers)
# systemd reads units from /usr/local/lib/systemd/system and sysusers files from
# /usr/local/lib/sysusers.d as well as from /usr/lib/..., so the default prefix works.
include(GNUInstallDirs)
set(ROBODIFF_SYSTEMD_UNIT_DIR "lib/systemd/system" CACHE STRING
    "Where cmake --install puts the systemd units (relative: under the install prefix)")
set(ROBODIFF_SYSUSERS_DIR "lib/sysusers.d" CACHE STRING
    "Where cmake --install puts the sysusers.d file (relative: under the install prefix)")

set(deploy_dir ${CMAKE_CURRENT_LIST_DIR})
install(FILES ${deploy_dir}/robodiffd.conf ${deploy_dir}/roudi.toml ${deploy_dir}/cyclonedds-loopback.xml
              ${deploy_dir}/cyclonedds-lan.xml
        DESTINATION ${CMAKE_INSTALL_DATADIR}/robodiff/deploy COMPONENT service)
install(FILES ${deploy_dir}/systemd/robodiff.sysusers DESTINATION ${ROBODIFF_SYSUSERS_DIR}
        RENAME robodiff.conf COMPONENT service)
# The rest depends on the prefix, which `cmake --install --prefix` may change: done at
# install time by a script, given the directories as configured.
install(CODE "
set(ROBODIFF_DEPLOY_DIR \"${deploy_dir}\")
set(ROBODIFF_STAGING_DIR \"${CMAKE_CURRENT_BINARY_DIR}/installed-units\")
set(ROBODIFF_BINDIR \"${CMAKE_INSTALL_BINDIR}\")
set(ROBODIFF_SYSCONFDIR \"${CMAKE_INSTALL_SYSCONFDIR}\")
set(ROBODIFF_DATADIR \"${CMAKE_INSTALL_DATADIR}\")
set(ROBODIFF_UNIT_DIR \"${ROBODIFF_SYSTEMD_UNIT_DIR}\")
include(\"${deploy_dir}/install_service_files.cmake\")
" COMPONENT service)
