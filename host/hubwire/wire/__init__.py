"""Wire layer: frames (CRC + COBS), message payloads and typed values."""
from .frame import Frame, FrameDecoder, crc16, encode_frame, decode_frame, max_encoded_length
from .messages import NakCode

__all__ = ["Frame", "FrameDecoder", "crc16", "encode_frame", "decode_frame", "max_encoded_length", "NakCode"]
