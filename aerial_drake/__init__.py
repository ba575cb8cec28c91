"""aerial_drake: the inertially decoupled task-space controller of Garofalo, Beck and Ott,
"Task-space tracking control for underactuated aerial manipulators", as Drake systems."""

__version__ = "0.1.0"
