"""The words the front doors accept, defined once (standard library only, so that every
floor may import it cheaply): the application floor's scene schema and command line read
them from here rather than spelling them again.
"""

__all__ = ["CHANNELS", "CONTACT_LAWS", "METHODS", "BOUNDARY_CONDITIONS"]

#: recorded signals of ``stochastic.simulate`` (``x``, ``v`` of the output DOF or ``x[i]``;
#: the base motion ``y`` and its velocity ``yd``; penetration ``delta`` and contact ``force`` of
#: element 0 or ``delta[e]``). Units: m, m/s, N.
CHANNELS = ("x", "v", "y", "yd", "delta", "force")
#: contact laws of ``nlbeam.Contact`` (``law``) and ``BeamImpact`` (``contact``)
CONTACT_LAWS = ("hertz", "lankarani-nikravesh", "hunt-crossley")
#: integration methods of ``nlbeam.integrate`` / ``flow`` and of the analyses
METHODS = ("rk2", "rk4", "adaptive")
#: ends of ``ModalBeam`` (``bc``)
BOUNDARY_CONDITIONS = ("clamped-free", "clamped-clamped")
