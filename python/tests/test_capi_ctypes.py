"""The C interface (libreprise.so, capi/include/reprise.h) through ctypes: the ABI check, a pan
made at twice the rate, bad arguments, a codec round trip. ctest sets REPRISE_CAPI_LIBRARY to the
built library; without it the tests are skipped."""
import ctypes as C
import math
import os
import unittest

import numpy as np

LIBRARY = os.environ.get("REPRISE_CAPI_LIBRARY")

# This test is a caller built against ABI 1.1 (its ConverterOptions ends before
# widen_silhouettes, added in 1.2): the library must keep taking it.
ABI_VERSION = (1 << 16) | 1
LIBRARY_ABI_VERSION = (1 << 16) | 4
OK, NEED_MORE = 0, 1
ERROR_INVALID_ARGUMENT, ERROR_ABI_MISMATCH, ERROR_BUFFER_TOO_SMALL = -1, -2, -3
R32_FLOAT, RG32_FLOAT, RGB32_FLOAT, RGBA32_FLOAT = 1, 2, 3, 4


class Image(C.Structure):
    _fields_ = [("data", C.c_void_p), ("width", C.c_int32), ("height", C.c_int32),
                ("stride", C.c_int64), ("format", C.c_int32), ("reserved", C.c_int32)]


class Camera(C.Structure):
    _fields_ = [("time", C.c_double), ("view", C.c_float * 16), ("projection", C.c_float * 16),
                ("prev_view", C.c_float * 16), ("prev_projection", C.c_float * 16),
                ("jitter", C.c_float * 2), ("near_plane", C.c_float), ("far_plane", C.c_float),
                ("valid", C.c_int32), ("reserved", C.c_int32)]


class GBuffer(C.Structure):
    _fields_ = [("struct_size", C.c_uint32), ("reset", C.c_int32), ("color", Image),
                ("depth", Image), ("motion", Image), ("normal", Image), ("id", Image),
                ("ui", Image), ("camera", Camera), ("fps", C.c_double)]


class ConverterOptions(C.Structure):
    _fields_ = [("struct_size", C.c_uint32), ("factor", C.c_int32), ("mode", C.c_int32),
                ("warp", C.c_int32), ("fill", C.c_int32), ("refine", C.c_int32),
                ("budget_db", C.c_float), ("composite_ui", C.c_int32)]


def image(array, fmt):
    """A reprise_image viewing a C-contiguous numpy array (rows, columns[, components])."""
    assert array.flags.c_contiguous
    return Image(array.ctypes.data, array.shape[1], array.shape[0], array.strides[0], fmt, 0)


def texture(height, width, shift):
    y, x = np.mgrid[0:height, 0:width].astype(np.float64) + 0.5
    x = x - shift
    return np.stack([0.5 + 0.3 * np.sin(x * 0.35 + c) * np.cos(y * 0.22 - c) for c in range(3)],
                    axis=-1).astype(np.float32)


@unittest.skipUnless(LIBRARY, "REPRISE_CAPI_LIBRARY is not set (ctest sets it)")
class CapiThroughCtypes(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        lib = C.CDLL(LIBRARY)
        lib.reprise_last_error.restype = C.c_char_p
        lib.reprise_abi_version.restype = C.c_uint32
        lib.reprise_converter_destroy.restype = None
        lib.reprise_encoder_destroy.restype = None
        lib.reprise_decoder_destroy.restype = None
        lib.reprise_decoder_send_packet.argtypes = [C.c_void_p, C.c_void_p, C.c_size_t]
        lib.reprise_encoder_receive_packet.argtypes = [C.c_void_p, C.c_void_p, C.c_size_t,
                                                       C.POINTER(C.c_size_t)]
        for name in ("converter", "encoder", "decoder"):
            getattr(lib, f"reprise_{name}_create").argtypes = [C.c_uint32, C.c_void_p, C.c_void_p]
        for name in ("gbuffer", "converter_options"):  # size_t arguments
            getattr(lib, f"reprise_{name}_init").argtypes = [C.c_void_p, C.c_size_t]
        cls.lib = lib

    def error(self):
        return self.lib.reprise_last_error().decode()

    def gbuffer(self, color, depth=None, motion=None):
        g = GBuffer()
        self.assertEqual(self.lib.reprise_gbuffer_init(C.byref(g), C.sizeof(g)), OK)
        g.color = image(color, RGB32_FLOAT if color.shape[-1] == 3 else RGBA32_FLOAT)
        if depth is not None:
            g.depth = image(depth, R32_FLOAT)
        if motion is not None:
            g.motion = image(motion, RG32_FLOAT)
        g.fps = 30.0
        return g

    def test_abi_version_is_checked_at_creation(self):
        self.assertEqual(self.lib.reprise_abi_version(), LIBRARY_ABI_VERSION)
        handle = C.c_void_p()
        status = self.lib.reprise_converter_create(2 << 16, None, C.byref(handle))
        self.assertEqual(status, ERROR_ABI_MISMATCH)
        self.assertIsNone(handle.value)
        self.assertIn("abi_version 2.0", self.error())
        options = ConverterOptions()
        self.assertEqual(self.lib.reprise_converter_options_init(C.byref(options), C.sizeof(options)), OK)
        options.struct_size += 12  # a newer caller's struct (1.2 and 1.3 added 4 bytes each)
        status = self.lib.reprise_converter_create(ABI_VERSION, C.byref(options), C.byref(handle))
        self.assertEqual(status, ERROR_ABI_MISMATCH)
        self.assertIn("options->struct_size", self.error())

    def test_pan_in_between_frame_is_the_half_shift(self):
        h, w, pan = 48, 64, 4
        options = ConverterOptions()
        self.lib.reprise_converter_options_init(C.byref(options), C.sizeof(options))
        self.assertEqual((options.factor, options.refine), (2, 1))
        converter = C.c_void_p()
        self.assertEqual(self.lib.reprise_converter_create(ABI_VERSION, C.byref(options), C.byref(converter)), OK)
        depth = np.full((h, w), 5.0, np.float32)
        motion = np.zeros((h, w, 2), np.float32)
        motion[..., 0] = -pan
        outputs = []
        for k in range(2):
            color = texture(h, w, pan * k)
            frame = self.gbuffer(color, depth, motion)
            frame.camera.time = k / 30.0
            self.assertEqual(self.lib.reprise_converter_send(converter, C.byref(frame)), OK, self.error())
            while True:
                width, height = C.c_int32(), C.c_int32()
                status = self.lib.reprise_converter_output_size(converter, C.byref(width), C.byref(height))
                if status == NEED_MORE:
                    break
                self.assertEqual((status, width.value, height.value), (OK, w, h))
                made = np.zeros((h, w, 4), np.float32)
                out = self.gbuffer(made)
                self.assertEqual(self.lib.reprise_converter_receive(converter, C.byref(out)), OK, self.error())
                outputs.append((made, out.camera.time))
        self.lib.reprise_converter_destroy(converter)
        self.assertEqual(len(outputs), 3)
        between, time = outputs[1]
        self.assertAlmostEqual(time, 1.0 / 60.0, places=6)
        interior = np.s_[:, 2 * pan:w - 2 * pan, :3]
        error = np.abs(between[interior] - texture(h, w, pan / 2)[interior]).max()
        repeated = np.abs(between[interior] - texture(h, w, 0)[interior]).max()
        self.assertLess(error, 1e-4)      # measured: 0 (a whole-pixel shift is exact)
        self.assertGreater(repeated, 0.1)

    def test_bad_arguments_are_errors_naming_the_field(self):
        converter = C.c_void_p()
        self.assertEqual(self.lib.reprise_converter_create(ABI_VERSION, None, C.byref(converter)), OK)
        color = np.zeros((8, 8, 3), np.float32)
        frame = self.gbuffer(color)
        frame.color.stride = 8 * 12 - 1
        self.assertEqual(self.lib.reprise_converter_send(converter, C.byref(frame)), ERROR_INVALID_ARGUMENT)
        self.assertIn("frame->color.stride", self.error())
        frame = self.gbuffer(color)
        frame.color.format = 99
        self.assertEqual(self.lib.reprise_converter_send(converter, C.byref(frame)), ERROR_INVALID_ARGUMENT)
        self.assertIn("frame->color.format 99", self.error())
        self.assertEqual(self.lib.reprise_converter_send(converter, None), ERROR_INVALID_ARGUMENT)
        self.assertIn("frame is NULL", self.error())
        self.lib.reprise_converter_destroy(converter)

    def test_codec_round_trip(self):
        h, w = 48, 64
        encoder, decoder = C.c_void_p(), C.c_void_p()
        self.assertEqual(self.lib.reprise_encoder_create(ABI_VERSION, None, C.byref(encoder)), OK)
        self.assertEqual(self.lib.reprise_decoder_create(ABI_VERSION, None, C.byref(decoder)), OK)
        color = texture(h, w, 0)
        depth = np.full((h, w), 3.0, np.float32)
        frame = self.gbuffer(color, depth)
        self.assertEqual(self.lib.reprise_encoder_send_frame(encoder, C.byref(frame)), OK, self.error())
        size = C.c_size_t()
        status = self.lib.reprise_encoder_receive_packet(encoder, None, 0, C.byref(size))
        self.assertEqual(status, ERROR_BUFFER_TOO_SMALL)
        packet = (C.c_uint8 * size.value)()
        self.assertEqual(self.lib.reprise_encoder_receive_packet(encoder, packet, size.value, C.byref(size)), OK)
        self.assertEqual(self.lib.reprise_decoder_send_packet(decoder, packet, size.value), OK, self.error())
        decoded = np.zeros((h, w, 4), np.float32)
        back = np.zeros((h, w), np.float32)
        out = self.gbuffer(decoded, back)
        self.assertEqual(self.lib.reprise_decoder_receive_frame(decoder, C.byref(out)), OK, self.error())
        mse = float(np.mean((decoded[..., :3] - color) ** 2))
        psnr = 10 * math.log10(1.0 / mse)
        self.assertGreater(psnr, 32.0)  # measured: 34.8 dB at the default qp 28
        np.testing.assert_array_equal(back, depth)  # lossless depth by default
        self.lib.reprise_encoder_destroy(encoder)
        self.lib.reprise_decoder_destroy(decoder)


if __name__ == "__main__":
    unittest.main()
