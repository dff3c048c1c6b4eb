"""thruster-hil transport: how frames get from one process to the other.

Not part of the interface contract (that is :mod:`dbc`: the DBC, codec, E2E protection);
this package carries frames and knows nothing of their meaning.

* :mod:`transport.spec`: bus specs (``INTERFACE:CHANNEL[?options]``) -> open python-can
  buses, the default bus of this host, per-mode options.
* :mod:`transport.lockstep`: frames of one instant handed over together, and lockstep
  waits that poll before they block.
* :mod:`transport.hilbus`: the portable cross-process bus ``hilbus``, a python-can
  interface plugin over Unix datagram sockets (where the kernel has no SocketCAN). Its
  parts: :mod:`transport.wire` (the record format, pure functions),
  :mod:`transport.channel` (channel directories, member socket files, permissions),
  :mod:`transport.peers` (the members one member sends to), :mod:`transport.inbox` (one
  member's receive side).

Dependencies: python-can, and :mod:`dbc.errors` (the project's single error module).
Never :mod:`bench` or :mod:`flight_sw`, which both import this package.
"""
