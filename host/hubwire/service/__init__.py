"""``hubwire serve``: one process owns the boards and shares them (the MQTT bridge is
:mod:`hubwire.service.mqtt`, Home Assistant discovery :mod:`hubwire.service.ha`)."""
