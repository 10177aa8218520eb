"""dyncal code generator: robot description -> fixed-size C++ dynamics headers."""
