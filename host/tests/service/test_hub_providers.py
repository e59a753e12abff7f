"""The service's table of hub channel providers (daemon/hub_providers.py), its Home Assistant
entities (bridge/hub_ha.py) and the dashboard's field, without a board: one provider per channel,
a second refused naming both, a channel declared on the board's session only while held (and, for
the MQTT bridge, once it has a value), released when its provider goes."""
from __future__ import annotations

import asyncio
from types import SimpleNamespace
from typing import Any, Dict, List

import pytest

from hubwire.descriptor.parse import parse_descriptor
from hubwire.errors import HubChannelError
from hubwire.hub import HubChannels
from hubwire.bridge.hub_ha import hub_discovery
from hubwire.daemon.hub_providers import HubConflict, HubProviders, Provider, entry_of
from hubwire.bridge.topics import Topics

THERMO = parse_descriptor(
    '{"p":1,"n":"thermostat","ch":[{"id":1,"n":"temperature","a":"r","t":"f32"}],"hub":['
    '{"id":1,"n":"setpoint","a":"r","t":"f32","u":"C"},{"id":2,"n":"report","a":"w","t":"u16"},'
    '{"id":3,"n":"alarm","a":"c","t":"f32","rt":"bool"},{"id":4,"n":"mode","a":"e","t":"u8"}]}')


class FakeFleet:
    def __init__(self) -> None:
        self.channels = HubChannels()
        self.channels.event("mode", type="u8")  # as the service offers every hub event
        dev = SimpleNamespace(core=SimpleNamespace(hub=SimpleNamespace(channels=self.channels)), descriptor=THERMO)
        self.board = SimpleNamespace(key="thermostat", device=dev, board_id=None)
        self.hub = HubProviders(self)

    def descriptor(self, key: str) -> Any:
        if key != "thermostat":
            raise KeyError(key)
        return THERMO

    def get(self, key: str) -> Any:
        self.descriptor(key)
        return self.board


class Answering(Provider):
    def __init__(self, label: str, value: float = 21.5, has_value: bool = True) -> None:
        super().__init__(label)
        self.value, self.has_value = value, has_value
        self.reports: List[int] = []

    def ready(self, key: str, name: str) -> bool:
        return self.has_value or name != "setpoint"

    async def read(self, key: str, name: str) -> Any:
        return self.value

    async def write(self, key: str, name: str, value: Any) -> Any:
        self.reports.append(value)
        return True


def entries(*names: str) -> List[Dict[str, Any]]:
    return [entry_of(c) for c in THERMO.hub if c.name in names]


def rows(fleet: FakeFleet) -> Dict[str, Dict[str, Any]]:
    return {r["channel"]: r for r in fleet.hub.status("thermostat")}


def test_one_provider_per_channel_and_the_second_is_refused_naming_both() -> None:
    fleet = FakeFleet()
    a, b = Answering("client 'a.py' (pid 1)"), Answering("MQTT (hubwire/<board>/hub/<channel>/set)")
    b.kind = "mqtt"
    fleet.hub.claim("thermostat", a, entries("setpoint", "report"))
    assert fleet.channels.get("setpoint") is not None and fleet.channels.get("report") is not None
    assert rows(fleet)["setpoint"] == {"channel": "setpoint", "access": "r", "type": "f32",
                                       "by": "client 'a.py' (pid 1)", "kind": "client", "bind": "ok", "status": "ok"}
    assert rows(fleet)["alarm"]["status"] == "unbound" and rows(fleet)["alarm"]["bind"] == "UNKNOWN_CHANNEL"
    assert rows(fleet)["mode"]["kind"] == "service" and rows(fleet)["mode"]["bind"] == "ok"
    with pytest.raises(HubConflict) as e:
        fleet.hub.claim("thermostat", b, entries("alarm", "report"))
    assert "client 'a.py' (pid 1)" in str(e.value) and "MQTT" in str(e.value) and "report" in str(e.value)
    assert fleet.hub.holder("thermostat", "alarm") is None  # all or none
    fleet.hub.release(a)
    assert fleet.channels.get("setpoint") is None and fleet.channels.get("report") is None
    assert rows(fleet)["setpoint"]["status"] == "unbound"
    fleet.hub.claim("thermostat", b, entries("report"))
    assert rows(fleet)["report"]["kind"] == "mqtt"


def test_a_declaration_the_board_does_not_expect_is_refused() -> None:
    fleet = FakeFleet()
    bad = [dict(entry_of(THERMO.hub[1]), t="u32")]
    with pytest.raises(HubChannelError, match="report"):
        fleet.hub.claim("thermostat", Answering("x"), bad)
    assert fleet.hub.holder("thermostat", "report") is None


def test_the_stand_ins_ask_the_provider_and_wait_for_a_first_value() -> None:
    async def main() -> None:
        fleet = FakeFleet()
        p = Answering("mqtt", 25.0, has_value=False)
        fleet.hub.claim("thermostat", p, entries("setpoint", "report"))
        assert fleet.channels.get("setpoint") is None and rows(fleet)["setpoint"]["status"] == "waiting"
        p.has_value = True
        fleet.hub.refresh("thermostat")
        hc = fleet.channels["setpoint"]
        assert hc.getter is not None and await hc.getter() == 25.0
        report = fleet.channels["report"]
        assert report.on_write is not None and await report.on_write(215) is True
        assert p.reports == [215]
    asyncio.run(main())


def test_home_assistant_gets_a_number_a_sensor_an_event_and_a_number_for_the_mode() -> None:
    msgs = dict(hub_discovery(Topics(), "pi", "thermostat", THERMO, None, ["setpoint", "report", "alarm", "mode"]))
    import json

    setpoint = json.loads(msgs["homeassistant/number/thermostat/hub-setpoint/config"])
    assert setpoint["command_topic"] == "hubwire/thermostat/hub/setpoint/set"
    assert setpoint["unique_id"] == "hubwire_thermostat--hub-setpoint" and setpoint["unit_of_measurement"] == "°C"
    assert json.loads(msgs["homeassistant/sensor/thermostat/hub-report/config"])["state_topic"] == \
        "hubwire/thermostat/hub/report"
    assert json.loads(msgs["homeassistant/event/thermostat/hub-alarm/config"])["event_types"] == ["alarm"]
    mode = json.loads(msgs["homeassistant/number/thermostat/hub-mode/config"])
    assert (mode["min"], mode["max"], mode["step"], mode["mode"]) == (0.0, 255.0, 1, "box")


def test_a_bool_event_is_a_select_and_a_bool_value_a_switch() -> None:
    import json

    desc = parse_descriptor('{"p":1,"n":"t","ch":[{"id":1,"n":"x","a":"r","t":"u8"}],'
                            '"hub":[{"id":1,"n":"away","a":"e","t":"bool"},{"id":2,"n":"armed","a":"r","t":"bool"}]}')
    msgs = dict(hub_discovery(Topics(), "pi", "t", desc, None, ["away", "armed"]))
    assert json.loads(msgs["homeassistant/select/t/hub-away/config"])["options"] == ["false", "true"]
    assert json.loads(msgs["homeassistant/switch/t/hub-armed/config"])["payload_on"] == "true"


def test_the_dashboard_feed_names_the_providers() -> None:
    from hubwire.dashboard.feed import BoardFeed

    fleet = FakeFleet()
    fleet.hub.claim("thermostat", Answering("client 'a.py' (pid 1)"), entries("setpoint"))
    feed = BoardFeed.__new__(BoardFeed)
    feed.key, feed.providers = "thermostat", fleet.hub
    assert feed.hub_providers() == {"setpoint": "client 'a.py' (pid 1)", "report": "", "alarm": "",
                                    "mode": "the service (notify)"}


def test_the_mqtt_bridge_takes_a_channel_when_its_client_goes(caplog: pytest.LogCaptureFixture) -> None:
    pytest.importorskip("aiomqtt")
    from hubwire.bridge.hub_topics import HubBridge

    async def main() -> None:
        fleet = FakeFleet()
        fleet.boards = lambda: [fleet.board]  # type: ignore[attr-defined]
        client = Answering("client 'heater.py' (pid 812)")
        fleet.hub.claim("thermostat", client, entries("setpoint"))
        bridge = HubBridge(fleet, "127.0.0.1", 1, ["thermostat/*"])
        remove = fleet.hub.watch(bridge._changed)
        bridge.sync("thermostat")
        assert fleet.hub.holder("thermostat", "setpoint") is client
        assert fleet.hub.holder("thermostat", "report") is bridge and fleet.hub.holder("thermostat", "alarm") is bridge
        assert "client 'heater.py' (pid 812)" in caplog.text and "MQTT" in caplog.text
        status = bridge.latest["hubwire/thermostat/hub"]
        assert "heater.py" in status
        fleet.hub.release(client)
        await asyncio.sleep(0.01)  # the bridge resyncs on the loop
        assert fleet.hub.holder("thermostat", "setpoint") is bridge
        assert rows(fleet)["setpoint"]["status"] == "waiting"  # no value from MQTT yet: not declared
        assert fleet.channels.get("setpoint") is None
        remove()
    asyncio.run(main())
