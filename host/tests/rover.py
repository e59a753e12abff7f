"""What examples/Rover declares (its channels.h), as the hub should discover it (emulator and simulated Uno)."""

ROVER = [
    # id, name, access letters, type as the hub names it, unit, min, max, failsafe
    (1, "left", "rws", "f32", "m/s", -1, 1, 0.0),
    (2, "right", "rws", "f32", "m/s", -1, 1, 0.0),
    (3, "imu", "rs", "struct{ax: f32, ay: f32, az: f32, gyro: i16[3]}", None, None, None, None),
    (4, "range", "rs", "u16[4]", "cm", None, None, None),
    (5, "battery", "rs", "u16", "mV", None, None, None),
    (6, "led", "rw", "bool", None, None, None, None),
    (7, "name", "rw", "str[16]", None, None, None, None),
    (8, "bumper", "e", "bool", None, None, None, None),
    (9, "beep", "c", "(u16) -> bool", None, None, None, None),
    (10, "selftest", "c", "(u8) -> u8", None, None, None, None),
    (11, "failsafes", "r", "u16", None, None, None, None),
    (12, "applied", "r", "u32", None, None, None, None),
]
