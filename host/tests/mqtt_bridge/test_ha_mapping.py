"""The entity mapping (docs/MQTT.md, "Entity mapping"), one test per row, on the examples' own
descriptors; the value templates rendered with Jinja as Home Assistant renders them (its
``to_json`` filter stood in by ``json.dumps``). tests/ha_real/ checks the same against a real
Home Assistant."""
from __future__ import annotations

import json
from typing import Any, Dict, Tuple

import jinja2

from hubwire.descriptor import parse_descriptor
from hubwire.bridge import ha
from hubwire.bridge.topics import Topics

from . import ha_documented as doc

ROVER = ('{"p":1,"n":"rover","fw":"1.0.0","ch":[{"id":1,"n":"left","a":"rws","t":"f32","u":"m/s","min":-1,"max":1,"fs":0},'
         '{"id":3,"n":"imu","a":"rs","t":"struct","f":[{"n":"ax","t":"f32"},{"n":"ay","t":"f32"},{"n":"az","t":"f32"},'
         '{"n":"gyro","t":"i16","c":3}]},{"id":4,"n":"range","a":"rs","t":"u16","c":4,"u":"cm"},'
         '{"id":5,"n":"battery","a":"rs","t":"u16","u":"mV"},{"id":6,"n":"led","a":"rw","t":"bool"},'
         '{"id":7,"n":"name","a":"rw","t":"str","c":16},{"id":8,"n":"bumper","a":"e","t":"bool"},'
         '{"id":9,"n":"beep","a":"c","t":"u16","rt":"bool"},{"id":10,"n":"selftest","a":"c","t":"u8","rt":"u8"},'
         '{"id":11,"n":"failsafes","a":"r","t":"u16"},{"id":12,"n":"applied","a":"r","t":"u32"}]}')
ACTIONS = ('{"p":1,"n":"actions","ch":[{"id":1,"n":"blink","a":"w","t":"u8"},{"id":2,"n":"read_pin","a":"c","t":"u8","rt":"i8"},'
           '{"id":3,"n":"uptime_ms","a":"c","t":"void","rt":"u32","u":"ms"},{"id":4,"n":"calls","a":"r","t":"u16"}]}')
LARGE = ('{"p":1,"n":"large","ch":[{"id":1,"n":"profile","a":"rw","t":"struct","f":[{"n":"gain","t":"f32","c":20},'
         '{"n":"table","t":"i16","c":40},{"n":"name","t":"u8","c":40}]},{"id":2,"n":"path","a":"rw","t":"i16","vc":12,'
         '"u":"cm","min":-1000,"max":1000},{"id":3,"n":"sum","a":"c","t":"u8","vc":16,"rt":"u16"},'
         '{"id":4,"n":"profile_writes","a":"r","t":"u16"}]}')
LAB = ('{"p":1,"n":"lab","ch":[{"id":1,"n":"temp","a":"rs","t":"f32","u":"C"},{"id":2,"n":"heating","a":"r","t":"bool"},'
       '{"id":3,"n":"humidity","a":"rs","t":"f32","u":"%"},{"id":4,"n":"duty","a":"rs","t":"f32","u":"%"},'
       '{"id":5,"n":"label","a":"r","t":"str","c":200},{"id":6,"n":"gain","a":"w","t":"f32"}]}')


def entities(raw: str, key: str = "b") -> Dict[Tuple[str, str], Dict[str, Any]]:
    """``{(platform, object_id or object_id--result): config}``; checks every key is documented."""
    desc = parse_descriptor(raw.encode())
    out: Dict[Tuple[str, str], Dict[str, Any]] = {}
    for topic, payload in ha.discovery_messages(Topics(), "host1", key, desc, None):
        m = doc.TOPIC.match(topic)
        assert m is not None, topic
        if not payload:
            continue  # a config of an earlier version, cleared
        cfg = json.loads(payload)
        kind = m["component"]
        assert set(cfg) <= doc.KEYS[kind], (kind, set(cfg) - doc.KEYS[kind])
        assert doc.REQUIRED[kind] <= set(cfg)
        suffix = "--result" if cfg["unique_id"].endswith("--result") else ""
        out[(kind, m["obj"] + suffix)] = cfg
    return out


_env = jinja2.Environment()
_env.filters["to_json"] = lambda v: json.dumps(v, separators=(",", ":"), ensure_ascii=False)


def render(template: str, payload: str) -> str:
    """What Home Assistant makes of ``payload`` with ``template`` (value and value_json)."""
    try:
        value_json: Any = json.loads(payload)
    except ValueError:
        value_json = None
    return _env.from_string(template).render(value=payload, value_json=value_json)


def test_an_array_with_a_unit_is_a_text_sensor_with_the_values_as_attributes() -> None:
    for raw, name in ((ROVER, "range"), (LARGE, "path")):
        cfg = entities(raw)[("sensor", name)]
        assert "unit_of_measurement" not in cfg and "state_class" not in cfg and "device_class" not in cfg
        assert render(cfg["value_template"], "[150,150,150,150]") == "[150,150,150,150]"
        assert cfg["json_attributes_topic"] == cfg["state_topic"]
        assert json.loads(render(cfg["json_attributes_template"], "[1,2]")) == {"values": [1, 2]}


def test_nan_published_as_null_makes_a_numeric_sensor_unknown_not_an_error() -> None:
    # Home Assistant's MQTT sensor takes the rendered "None" as no value (state unknown); the raw
    # payload "null" on a measurement sensor is an error and the last number stays
    for key, cfg in entities(LAB).items():
        if cfg.get("state_class") == "measurement":
            assert render(cfg["value_template"], "null") == "None", key
            assert render(cfg["value_template"], "21.5") == "21.5"
    left = entities(ROVER)[("number", "left")]
    assert render(left["value_template"], "null") == "None"  # a number's payload_reset


def test_a_struct_is_a_sensor_with_its_fields_as_attributes_and_a_state_under_256() -> None:
    cfg = entities(LARGE)[("sensor", "profile")]
    value = {"gain": [1.25] * 20, "table": [-1000] * 40, "name": [65] * 40}
    payload = json.dumps(value, separators=(",", ":"))
    assert len(payload) > 255
    state = render(cfg["value_template"], payload)
    assert len(state) <= 255 and state.endswith("...")
    assert json.loads(render(cfg["json_attributes_template"], payload)) == value
    imu = entities(ROVER)[("sensor", "imu")]
    assert render(imu["value_template"], '{"ax":0.0}') == '{"ax":0.0}' and "unit_of_measurement" not in imu


def test_a_write_only_number_is_not_optimistic_its_state_is_what_the_board_accepted() -> None:
    cfg = entities(ACTIONS)[("number", "blink")]
    assert cfg["state_topic"] == "hubwire/b/state/blink" and "optimistic" not in cfg
    assert (cfg["min"], cfg["max"], cfg["step"]) == (0, 255, 1)


def test_read_only_bool_is_a_binary_sensor() -> None:
    cfg = entities(LAB)[("binary_sensor", "heating")]
    assert (cfg["payload_on"], cfg["payload_off"]) == ("true", "false")


def test_writable_string_is_a_text_entity_sending_json() -> None:
    cfg = entities(ROVER)[("text", "name")]
    assert cfg["command_topic"] == "hubwire/b/set/name" and cfg["max"] == 16
    assert render(cfg["command_template"].replace("value |", "value_json |"), '"a \\"b\\""') == '"a \\"b\\""'
    assert render(cfg["value_template"], '"rover"') == "rover"


def test_units_give_device_classes_and_home_assistant_spellings() -> None:
    got = entities(ROVER)
    assert (got[("sensor", "battery")]["device_class"], got[("sensor", "battery")]["unit_of_measurement"]) == ("voltage", "mV")
    assert (got[("number", "left")]["device_class"], got[("number", "left")]["unit_of_measurement"]) == ("speed", "m/s")
    lab = entities(LAB)
    assert (lab[("sensor", "temp")]["device_class"], lab[("sensor", "temp")]["unit_of_measurement"]) == ("temperature", "°C")
    assert lab[("sensor", "humidity")]["device_class"] == "humidity"
    assert "device_class" not in lab[("sensor", "duty")] and lab[("sensor", "duty")]["unit_of_measurement"] == "%"


def test_floats_get_a_display_precision_integers_do_not() -> None:
    lab = entities(LAB)
    assert lab[("sensor", "temp")]["suggested_display_precision"] == 2
    assert "suggested_display_precision" not in entities(ROVER)[("sensor", "battery")]


def test_counters_are_total_increasing_and_diagnostic() -> None:
    for raw, name in ((ROVER, "failsafes"), (ROVER, "applied"), (ACTIONS, "calls"), (LARGE, "profile_writes")):
        cfg = entities(raw)[("sensor", name)]
        assert (cfg["state_class"], cfg["entity_category"]) == ("total_increasing", "diagnostic"), name
    assert "entity_category" not in entities(ROVER)[("sensor", "battery")]


def test_names_are_readable_and_the_device_too() -> None:
    got = entities(ACTIONS, key="actions--A1")
    assert got[("button", "uptime_ms")]["name"] == "Uptime"
    assert got[("sensor", "uptime_ms--result")]["name"] == "Uptime result"
    assert got[("number", "read_pin")]["name"] == "Read pin"
    assert got[("button", "uptime_ms")]["device"]["name"] == "Actions A1"
    assert entities(ROVER)[("sensor", "battery")]["name"] == "Battery"


def test_actions_with_an_argument_are_a_number_or_text_that_calls_and_a_result_sensor() -> None:
    got = entities(ROVER)
    beep = got[("number", "beep")]
    assert beep["command_topic"] == "hubwire/b/call/beep" and beep["state_topic"] == "hubwire/b/result/beep"
    assert render(beep["value_template"], '{"arg":200,"value":true}') == "200"
    res = got[("binary_sensor", "beep--result")]
    assert res["state_topic"] == "hubwire/b/result/beep"
    assert render(res["value_template"], '{"arg":200,"value":true}') == "ON"
    total = entities(LARGE)[("text", "sum")]
    assert total["command_template"] == "{{ value }}" and total["command_topic"] == "hubwire/b/call/sum"
    assert render(total["value_template"], '{"arg":[1,2],"value":3}') == "[1,2]"
    long_arg = json.dumps({"arg": list(range(1000, 1064)), "value": 1})  # u32[<=64]: over 255 as JSON
    assert len(render(total["value_template"], long_arg)) == 255  # a text entity's state stays valid
    assert total["max"] == 255  # characters of JSON text; the list's capacity (16) counts elements
    assert render(entities(LARGE)[("sensor", "sum--result")]["value_template"], '{"arg":[1,2],"value":3}') == "3"


def test_a_button_result_is_a_sensor_of_the_result_topic() -> None:
    got = entities(ACTIONS)
    assert got[("button", "uptime_ms")]["command_topic"] == "hubwire/b/call/uptime_ms"
    res = got[("sensor", "uptime_ms--result")]
    assert (res["device_class"], res["unit_of_measurement"]) == ("duration", "ms")
    assert render(res["value_template"], '{"arg":null,"value":1234}') == "1234"


def test_an_entity_that_moved_platform_clears_the_config_of_earlier_versions() -> None:
    desc = parse_descriptor(ROVER.encode())
    msgs = dict(ha.discovery_messages(Topics(), "host1", "b", desc, None))
    assert msgs["homeassistant/sensor/b/name/config"] == ""  # was a sensor, now text
    assert msgs["homeassistant/text/b/name/config"]
    assert "homeassistant/sensor/b/battery/config" in msgs and msgs["homeassistant/sensor/b/battery/config"]


MISSIONS = ('{"p":1,"n":"missions","ch":[{"id":1,"n":"drive","a":"m","t":"f32","u":"m","min":0.1,"max":10,'
            '"rt":"f32","pt":"f32","pmax":10},{"id":2,"n":"speed","a":"rw","t":"f32","u":"m/s","min":0.1,"max":2}]}')
THERMO = ('{"p":1,"n":"thermostat","fw":"1.0","ch":[{"id":1,"n":"temperature","a":"r","t":"f32","u":"C"}],"hub":['
          '{"id":1,"n":"setpoint","a":"r","t":"f32","u":"C"},{"id":2,"n":"report","a":"w","t":"u16"},'
          '{"id":3,"n":"alarm","a":"c","t":"f32","rt":"bool"},{"id":4,"n":"mode","a":"e","t":"u8"},'
          '{"id":5,"n":"away","a":"e","t":"bool"}]}')


def test_a_mission_is_a_sensor_of_its_last_run() -> None:
    cfg = entities(MISSIONS)[("sensor", "drive")]
    assert cfg["state_topic"] == cfg["json_attributes_topic"] == "hubwire/b/mission/drive/state"
    assert cfg["name"] == "Drive" and cfg["unique_id"] == "hubwire_b--drive"
    assert "unit_of_measurement" not in cfg and "state_class" not in cfg and "device_class" not in cfg
    state = '{"run_id":"ha-1","run":3,"status":"succeeded","progress":0.4,"received":4,"value":0.5}'
    assert render(cfg["value_template"], state) == "succeeded"
    assert render(cfg["value_template"], '{"run_id":"x","status":"link lost"}') == "link lost"
    assert set(entities(MISSIONS)) == {("sensor", "drive"), ("number", "speed")}


def hub_entities(raw: str, key: str = "b") -> Dict[Tuple[str, str], Dict[str, Any]]:
    """The hub channels' entities, every key checked as for a board channel."""
    from hubwire.bridge.hub_ha import hub_discovery

    desc = parse_descriptor(raw.encode())
    out: Dict[Tuple[str, str], Dict[str, Any]] = {}
    for topic, payload in hub_discovery(Topics(), "host1", key, desc, "A1", [c.name for c in desc.hub]):
        m = doc.TOPIC.match(topic)
        assert m is not None, topic
        cfg = json.loads(payload)
        kind = m["component"]
        assert set(cfg) <= doc.KEYS[kind], (kind, set(cfg) - doc.KEYS[kind])
        assert doc.REQUIRED[kind] <= set(cfg)
        out[(kind, m["obj"])] = cfg
    return out


def test_hub_channels_join_the_boards_device_with_readable_names_and_unit_classes() -> None:
    key = "thermostat--A1"
    desc = parse_descriptor(THERMO.encode())
    board = ha.entity_configs(Topics(), "host1", key, desc, "A1", desc.channels[0])[0][1]
    hub = hub_entities(THERMO, key)
    assert set(hub) == {("number", "hub-setpoint"), ("sensor", "hub-report"), ("event", "hub-alarm"),
                        ("number", "hub-mode"), ("select", "hub-away")}
    for cfg in hub.values():
        # one device: the same name, so HA does not rename it to whichever config came last
        assert cfg["device"] == board["device"] and cfg["device"]["name"] == "Thermostat A1"
    setpoint = hub[("number", "hub-setpoint")]
    assert setpoint["name"] == "Hub setpoint"
    assert (setpoint["device_class"], setpoint["unit_of_measurement"]) == ("temperature", "°C")
    assert render(setpoint["value_template"], "null") == "None"  # a NaN: unknown, not an error
    assert render(setpoint["value_template"], "21.5") == "21.5"
    assert hub[("sensor", "hub-report")]["state_class"] == "measurement"


def test_what_the_board_writes_or_calls_is_unavailable_with_the_board_the_hubs_values_are_not() -> None:
    hub = hub_entities(THERMO, "thermostat")
    service = {"topic": "hubwire/_service/host1/status", "payload_available": "online", "payload_not_available": "offline"}
    board = dict(service, topic="hubwire/thermostat/status")
    for key in (("sensor", "hub-report"), ("event", "hub-alarm")):
        assert hub[key]["availability"] == [service, board] and hub[key]["availability_mode"] == "all", key
    for key in (("number", "hub-setpoint"), ("number", "hub-mode"), ("select", "hub-away")):
        assert hub[key]["availability"] == [service], key  # set while the board is away: it gets it when back
