"""Bridges to other libraries, each imported only inside its functions.

``mechcirc.interop.skrf``     scikit-rf networks and Touchstone files (one- and two-ports)
``mechcirc.interop.formula``  K(ω) as a SymPy expression built from the reduction tree
"""
