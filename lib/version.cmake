# dyncal's version: the project's and the installed package's (dyncalConfigVersion.cmake).
set(DYNCAL_VERSION 0.1.0)
