"""``hubwire serve``: one process owns the boards and shares them (docs/SERVICE.md). ``fleet`` keeps
the boards, ``ports`` finds them, ``server`` serves them on the Unix socket, ``store`` and
``durable`` keep what survives a restart. The MQTT bridge is :mod:`hubwire.bridge`; the programs
that use the service reach it through :mod:`hubwire.client`."""
