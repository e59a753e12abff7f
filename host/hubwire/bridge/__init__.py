"""The MQTT bridge of ``hubwire serve`` (docs/MQTT.md): ``mqtt`` (:func:`run_bridge`), ``board``
(one board on the broker), ``topics``, ``outbox``, ``inbound``, ``reply``, ``retire``, ``broker``
(reaching the broker) and ``ha`` (Home Assistant discovery)."""
