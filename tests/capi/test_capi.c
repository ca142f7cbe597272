/* The C interface from C (reprise.h): a pan upconverted to the expected shift, a reported cut,
 * the other eye of a plane at the expected disparity, a codec round trip, the ABI check and bad
 * arguments. Prints each figure it checks; exits 1 when any check failed. */
#include "reprise.h" /* first: the header compiles alone */

#include <math.h>
#include <pthread.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { W = 64, H = 48, PAN = 4 };

static int failures = 0;

#define CHECK(cond, ...)                                                             \
    do {                                                                             \
        if (!(cond)) {                                                               \
            fprintf(stderr, "%s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                            \
            fprintf(stderr, " (last error: %s)\n", reprise_last_error());            \
            ++failures;                                                              \
        }                                                                            \
    } while (0)

#define EXPECT_STATUS(call, expected)                                                          \
    do {                                                                                       \
        reprise_status got_ = (call);                                                          \
        CHECK(got_ == (expected), "%s gave %s, expected %s", #call, reprise_status_name(got_), \
              reprise_status_name(expected));                                                  \
    } while (0)

/* A smooth texture, as seen with the content moved `shift` pixels right: value at column x is
 * the texture's at x - shift. */
static float texture(double x, double y, int c) {
    const double u = x + 0.5, v = y + 0.5;
    return (float)(0.5 + 0.3 * sin(u * 0.35 + c) * cos(v * 0.22 - c) +
                   0.1 * sin(u * 0.11 + v * 0.07));
}

static void fill_pan(float* rgb, int stride_floats, int shift) {
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x)
            for (int c = 0; c < 3; ++c)
                rgb[y * stride_floats + x * 3 + c] = texture(x - shift, y, c);
}

static reprise_image image(void* data, int64_t stride, reprise_format format) {
    reprise_image i;
    memset(&i, 0, sizeof i);
    i.data = data;
    i.width = W;
    i.height = H;
    i.stride = stride;
    i.format = format;
    return i;
}

/* A 30 Hz frame: RGB float colour rows `rgb_stride` bytes apart, float depth and motion. */
static reprise_gbuffer rendered_frame(float* rgb, int64_t rgb_stride, float* depth, float* motion) {
    reprise_gbuffer frame;
    reprise_gbuffer_init(&frame, sizeof frame);
    frame.color = image(rgb, rgb_stride, REPRISE_FORMAT_RGB32_FLOAT);
    frame.depth = image(depth, W * 4, REPRISE_FORMAT_R32_FLOAT);
    frame.motion = image(motion, W * 8, REPRISE_FORMAT_RG32_FLOAT);
    frame.fps = 30.0;
    return frame;
}

/* Every pixel at `z` moving `dx` px right per frame (motion -dx). */
static void fill_depth_motion(float* depth, float* motion, float z, float dx) {
    for (int i = 0; i < H * W; ++i) {
        depth[i] = z;
        motion[2 * i] = -dx; /* content moving right has negative x motion */
        motion[2 * i + 1] = 0.0f;
    }
}

/* PSNR (dB, linear values, peak 1) of RGBA `made` against the texture at `shift`, over columns
 * margin .. W - margin. */
static double pan_psnr(const float* made, double shift, int margin) {
    double sum = 0.0;
    int n = 0;
    for (int y = 0; y < H; ++y)
        for (int x = margin; x < W - margin; ++x)
            for (int c = 0; c < 3; ++c) {
                const double d = made[(y * W + x) * 4 + c] - texture(x - shift, y, c);
                sum += d * d;
                ++n;
            }
    return sum == 0.0 ? INFINITY : 10.0 * log10((double)n / sum); /* inf: identical */
}

static float half_to_float(uint16_t h) {
    const int sign = h >> 15, exponent = (h >> 10) & 31, mantissa = h & 1023;
    double value;
    if (exponent == 0)
        value = ldexp(mantissa, -24);
    else if (exponent == 31)
        value = mantissa ? NAN : INFINITY;
    else
        value = ldexp(mantissa + 1024, exponent - 25);
    return (float)(sign ? -value : value);
}

/* Three frames of a pan, PAN px right per frame, without a camera: 30 -> 60 Hz. */
static void test_converter_pan(void) {
    static float rgb[H][W * 3 + 5]; /* padded rows: a stride larger than the row */
    static float depth[H * W], motion[H * W * 2], out_color[H * W * 4], out_motion[H * W * 2];
    static uint16_t out_half[H * W * 3];
    fill_depth_motion(depth, motion, 5.0f, PAN);
    reprise_converter_options options;
    EXPECT_STATUS(reprise_converter_options_init(&options, sizeof options), REPRISE_OK);
    CHECK(options.factor == 2 && options.refine == 1, "defaults factor %d refine %d",
          options.factor, options.refine);
    reprise_converter* converter = NULL;
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, &options, &converter), REPRISE_OK);
    if (!converter) return;

    int outputs = 0;
    for (int k = 0; k < 3; ++k) {
        fill_pan(&rgb[0][0], W * 3 + 5, PAN * k);
        reprise_gbuffer frame = rendered_frame(&rgb[0][0], (int64_t)sizeof rgb[0], depth, motion);
        frame.camera.time = k / 30.0;
        EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_OK);
        for (;;) {
            int32_t w = 0, h = 0;
            const reprise_status size = reprise_converter_output_size(converter, &w, &h);
            if (size == REPRISE_NEED_MORE) break;
            CHECK(size == REPRISE_OK && w == W && h == H, "output size %dx%d", w, h);
            reprise_gbuffer out;
            reprise_gbuffer_init(&out, sizeof out);
            const int passed = outputs % 2 == 0; /* input frames pass through, in-betweens made */
            if (k == 0) {
                /* The first frame passes through: written as half, it equals the input to half's
                 * precision. */
                out.color = image(out_half, W * 6, REPRISE_FORMAT_RGB16_FLOAT);
                EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_OK);
                double worst = 0.0;
                for (int y = 0; y < H; ++y)
                    for (int x = 0; x < W * 3; ++x) {
                        const double e = fabs(half_to_float(out_half[y * W * 3 + x]) - rgb[y][x]);
                        if (e > worst) worst = e;
                    }
                printf("converter: first frame through RGB16_FLOAT: largest error %.2e\n", worst);
                CHECK(worst <= 1.0 / 2048.0, "half output differs by %g", worst);
            } else {
                out.color = image(out_color, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
                out.motion = image(out_motion, W * 8, REPRISE_FORMAT_RG32_FLOAT);
                EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_OK);
                /* Output n shows time n / 60: the content has moved n * PAN / 2 pixels. */
                const double shift = outputs * PAN / 2.0;
                const double psnr = pan_psnr(out_color, shift, 2 * PAN);
                printf("converter: output %d (%s, shift %.0f px): PSNR %.2f dB, time %.4f s\n",
                       outputs, passed ? "input" : "made", shift, psnr, out.camera.time);
                CHECK(psnr > 60.0, "output %d PSNR %.2f dB against the %.0f px shift", outputs,
                      psnr, shift);
                CHECK(fabs(out.camera.time - outputs / 60.0) < 1e-6, "output %d time %g", outputs,
                      out.camera.time);
                /* Motion per output period: half the input's. */
                CHECK(fabsf(out_motion[(H / 2 * W + W / 2) * 2] + PAN / 2.0f) < 1e-3f,
                      "output %d motion %g", outputs, out_motion[(H / 2 * W + W / 2) * 2]);
                if (!passed) {
                    const double repeat = pan_psnr(out_color, shift - PAN / 2.0, 2 * PAN);
                    printf("converter: repeating the frame before instead: PSNR %.2f dB\n", repeat);
                    CHECK(psnr > repeat + 15.0, "made %.2f dB, repeated %.2f dB", psnr, repeat);
                }
            }
            ++outputs;
        }
    }
    CHECK(outputs == 5, "%d outputs from 3 inputs at factor 2 (interpolation: 1 + 2 + 2)", outputs);
    EXPECT_STATUS(reprise_converter_flush(converter), REPRISE_OK);
    reprise_gbuffer out;
    reprise_gbuffer_init(&out, sizeof out);
    out.color = image(out_color, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_NEED_MORE);
    reprise_converter_destroy(converter);
}

/* The pan's second frame 10 % brighter: interpolation blends the two frames' colours; with
 * reset (a cut the renderer reports) the frame between continues the first frame alone. Gives
 * the in-between frame's PSNR against the first frame's texture moved 2 px. */
static double in_between_after(int reset) {
    float rgb[H * W * 3], depth[H * W], motion[H * W * 2], made[H * W * 4]; /* per thread */
    fill_depth_motion(depth, motion, 5.0f, PAN);
    reprise_converter* converter = NULL;
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, NULL, &converter), REPRISE_OK);
    if (!converter) return 0.0;
    double psnr = 0.0;
    for (int k = 0; k < 2; ++k) {
        fill_pan(rgb, W * 3, PAN * k);
        for (int i = 0; i < H * W * 3; ++i) rgb[i] *= k ? 1.1f : 1.0f;
        reprise_gbuffer frame = rendered_frame(rgb, W * 12, depth, motion);
        frame.reset = k == 1 ? reset : 0;
        EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_OK);
        reprise_gbuffer out;
        reprise_gbuffer_init(&out, sizeof out);
        out.color = image(made, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
        EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_OK);
        if (k == 1) psnr = pan_psnr(made, PAN / 2.0, 2 * PAN); /* the frame between */
    }
    reprise_converter_destroy(converter);
    return psnr;
}

static void test_converter_reset(void) {
    const double blended = in_between_after(REPRISE_RESET_UNKNOWN),
                 continued = in_between_after(REPRISE_RESET_YES),
                 said_none = in_between_after(REPRISE_RESET_NO);
    printf(
        "converter: frame between against the first frame moved 2 px: %.2f dB blended, "
        "%.2f dB after a reset, %.2f dB when told none came\n",
        blended, continued, said_none);
    CHECK(continued > 60.0, "after a reset: %.2f dB", continued);
    CHECK(blended < 40.0, "without: %.2f dB", blended);
    CHECK(said_none == blended, "told no cut: %.2f dB, untold %.2f dB", said_none, blended);
}

/* A plane at depth 4 seen by the left eye; the right eye, ipd 0.5 and focal length 32 px, sees
 * it 32 * 0.5 / 4 = 4 px further left. */
static void test_stereo_plane(void) {
    static float rgba[H * W * 4], depth[H * W], made[H * W * 4], made_depth[H * W];
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            for (int c = 0; c < 3; ++c) rgba[(y * W + x) * 4 + c] = texture(x, y, c);
            rgba[(y * W + x) * 4 + 3] = 1.0f;
            depth[y * W + x] = 4.0f;
        }
    reprise_gbuffer rendered;
    reprise_gbuffer_init(&rendered, sizeof rendered);
    rendered.color = image(rgba, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    rendered.depth = image(depth, W * 4, REPRISE_FORMAT_R32_FLOAT);
    reprise_camera* camera = &rendered.camera;
    const float n = 0.1f, f = 100.0f;
    for (int i = 0; i < 16; i += 5) camera->view[i] = camera->prev_view[i] = 1.0f;
    camera->projection[0] = 1.0f; /* focal length 1 * W / 2 = 32 px */
    camera->projection[5] = (float)W / H;
    camera->projection[10] = -(f + n) / (f - n);
    camera->projection[11] = -1.0f;
    camera->projection[14] = -2.0f * f * n / (f - n);
    memcpy(camera->prev_projection, camera->projection, sizeof camera->projection);
    camera->valid = 1;
    camera->near_plane = n;
    camera->far_plane = f;

    reprise_stereo_options options;
    reprise_stereo_options_init(&options, sizeof options);
    options.ipd = 0.5f;
    reprise_stereo* stereo = NULL;
    EXPECT_STATUS(reprise_stereo_create(REPRISE_ABI_VERSION, &options, &stereo), REPRISE_OK);
    if (!stereo) return;
    reprise_gbuffer eye;
    reprise_gbuffer_init(&eye, sizeof eye);
    eye.color = image(made, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    eye.depth = image(made_depth, W * 4, REPRISE_FORMAT_R32_FLOAT);
    EXPECT_STATUS(reprise_stereo_synthesize(stereo, &rendered, &eye), REPRISE_OK);
    const double psnr = pan_psnr(made, -4.0, 8);
    const double unshifted = pan_psnr(made, 0.0, 8);
    printf("stereo: right eye against the 4 px shift: PSNR %.2f dB (unshifted %.2f dB), depth %g\n",
           psnr, unshifted, made_depth[H / 2 * W + W / 2]);
    CHECK(psnr > 40.0, "right eye PSNR %.2f dB", psnr);
    CHECK(psnr > unshifted + 15.0, "shifted %.2f, unshifted %.2f", psnr, unshifted);
    CHECK(fabsf(made_depth[H / 2 * W + W / 2] - 4.0f) < 1e-3f, "depth %g",
          made_depth[H / 2 * W + W / 2]);
    /* The made eye's camera sits ipd to the right: its view translates x by -ipd. */
    CHECK(eye.camera.valid == 1 && fabsf(eye.camera.view[12] + 0.5f) < 1e-6f, "right eye view x %g",
          eye.camera.view[12]);
    /* The rendered eye without a camera has no disparity: refused, naming the field. */
    rendered.camera.valid = 0;
    EXPECT_STATUS(reprise_stereo_synthesize(stereo, &rendered, &eye),
                  REPRISE_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(reprise_last_error(), "rendered->camera") != NULL, "message names the camera");
    reprise_stereo_destroy(stereo);
}

/* Encode three frames, decode them: sizes, PSNR and the depth back bit for bit (lossless). */
static void test_codec_round_trip(void) {
    static float rgb[H][W * 3], depth[H * W], motion[H * W * 2], color_back[H * W * 4],
        depth_back[H * W];
    static uint8_t packet[1 << 16];
    for (int i = 0; i < H * W; ++i) {
        depth[i] = 3.0f + (float)(i % W) / W;
        motion[2 * i] = -2.0f;
        motion[2 * i + 1] = 0.0f;
    }
    reprise_encoder_options eo;
    reprise_encoder_options_init(&eo, sizeof eo);
    eo.qp = 20;
    reprise_encoder* encoder = NULL;
    reprise_decoder* decoder = NULL;
    EXPECT_STATUS(reprise_encoder_create(REPRISE_ABI_VERSION, &eo, &encoder), REPRISE_OK);
    EXPECT_STATUS(reprise_decoder_create(REPRISE_ABI_VERSION, NULL, &decoder), REPRISE_OK);
    if (!encoder || !decoder) return;
    size_t total = 0;
    for (int k = 0; k < 3; ++k) {
        fill_pan(&rgb[0][0], W * 3, 2 * k);
        reprise_gbuffer frame = rendered_frame(&rgb[0][0], W * 12, depth, motion);
        EXPECT_STATUS(reprise_encoder_send_frame(encoder, &frame), REPRISE_OK);
        size_t size = 0;
        /* Asked without a buffer: the size, and the packet is kept. */
        EXPECT_STATUS(reprise_encoder_receive_packet(encoder, NULL, 0, &size),
                      REPRISE_ERROR_BUFFER_TOO_SMALL);
        CHECK(size > 0 && size <= sizeof packet, "packet size %zu", size);
        size_t got = 0;
        EXPECT_STATUS(reprise_encoder_receive_packet(encoder, packet, sizeof packet, &got),
                      REPRISE_OK);
        CHECK(got == size, "packet %zu bytes, announced %zu", got, size);
        EXPECT_STATUS(reprise_encoder_receive_packet(encoder, packet, sizeof packet, &got),
                      REPRISE_NEED_MORE);
        total += size;
        EXPECT_STATUS(reprise_decoder_send_packet(decoder, packet, size), REPRISE_OK);
        int32_t w = 0, h = 0;
        EXPECT_STATUS(reprise_decoder_output_size(decoder, &w, &h), REPRISE_OK);
        CHECK(w == W && h == H, "decoded size %dx%d", w, h);
        reprise_gbuffer out;
        reprise_gbuffer_init(&out, sizeof out);
        out.color = image(color_back, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
        out.depth = image(depth_back, W * 4, REPRISE_FORMAT_R32_FLOAT);
        EXPECT_STATUS(reprise_decoder_receive_frame(decoder, &out), REPRISE_OK);
        const double psnr = pan_psnr(color_back, 2 * k, 0);
        printf("codec: frame %d: %zu bytes, decoded PSNR %.2f dB\n", k, size, psnr);
        CHECK(psnr > 35.0, "frame %d decoded PSNR %.2f dB", k, psnr);
        CHECK(memcmp(depth, depth_back, sizeof depth) == 0, "frame %d lossless depth differs", k);
        EXPECT_STATUS(reprise_decoder_receive_frame(decoder, &out), REPRISE_NEED_MORE);
    }
    printf("codec: 3 frames in %zu bytes\n", total);
    /* A damaged packet is an error, not a crash; the decoder stays usable. */
    packet[8] ^= 0x5a;
    EXPECT_STATUS(reprise_decoder_send_packet(decoder, packet, 40), REPRISE_ERROR_INVALID_DATA);
    CHECK(strlen(reprise_last_error()) > 0, "a message for the damaged packet");
    reprise_encoder_destroy(encoder);
    reprise_decoder_destroy(decoder);
}

static void test_abi_mismatch(void) {
    reprise_converter* converter = (reprise_converter*)&failures; /* must be reset to NULL */
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION + (1u << 16), NULL, &converter),
                  REPRISE_ERROR_ABI_MISMATCH);
    CHECK(converter == NULL, "no handle on a mismatch");
    char newer[32];
    snprintf(newer, sizeof newer, "abi_version 2.%d", REPRISE_ABI_VERSION_MINOR);
    CHECK(strstr(reprise_last_error(), newer) != NULL, "message: %s", reprise_last_error());
    reprise_decoder* decoder = NULL;
    EXPECT_STATUS(reprise_decoder_create(REPRISE_ABI_VERSION + 1, NULL, &decoder),
                  REPRISE_ERROR_ABI_MISMATCH);
    /* A struct from a newer reprise.h (larger) or smaller than the first minor's is refused. */
    reprise_stereo_options options;
    reprise_stereo_options_init(&options, sizeof options);
    options.struct_size += 4;
    reprise_stereo* stereo = NULL;
    EXPECT_STATUS(reprise_stereo_create(REPRISE_ABI_VERSION, &options, &stereo),
                  REPRISE_ERROR_ABI_MISMATCH);
    CHECK(strstr(reprise_last_error(), "options->struct_size") != NULL, "message: %s",
          reprise_last_error());
    options.struct_size = offsetof(reprise_stereo_options, temporal);
    EXPECT_STATUS(reprise_stereo_create(REPRISE_ABI_VERSION, &options, &stereo),
                  REPRISE_ERROR_ABI_MISMATCH);
    /* Between the two sizes: no header ever had such a struct. */
    options.struct_size = offsetof(reprise_stereo_options, widen_silhouettes) + 1;
    EXPECT_STATUS(reprise_stereo_create(REPRISE_ABI_VERSION, &options, &stereo),
                  REPRISE_ERROR_ABI_MISMATCH);
    /* A minor-1 caller's struct ends before widen_silhouettes: init writes only its bytes and
     * create takes it. */
    unsigned char old[sizeof(reprise_stereo_options) + 8];
    memset(old, 0xab, sizeof old);
    const size_t old_size = offsetof(reprise_stereo_options, widen_silhouettes);
    EXPECT_STATUS(reprise_stereo_options_init((reprise_stereo_options*)old, old_size), REPRISE_OK);
    CHECK(old[old_size] == 0xab && old[sizeof old - 1] == 0xab, "init wrote past struct_size");
    EXPECT_STATUS(reprise_stereo_create(REPRISE_ABI_VERSION, (reprise_stereo_options*)old, &stereo),
                  REPRISE_OK);
    reprise_stereo_destroy(stereo);
    reprise_converter_options old_converter;
    memset(&old_converter, 0xab, sizeof old_converter);
    EXPECT_STATUS(reprise_converter_options_init(
                      &old_converter, offsetof(reprise_converter_options, widen_silhouettes)),
                  REPRISE_OK);
    reprise_converter* taken = NULL;
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, &old_converter, &taken),
                  REPRISE_OK);
    reprise_converter_destroy(taken);
    /* A minor-2 caller's struct ends before perceptual: taken too. */
    EXPECT_STATUS(reprise_converter_options_init(&old_converter,
                                                 offsetof(reprise_converter_options, perceptual)),
                  REPRISE_OK);
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, &old_converter, &taken),
                  REPRISE_OK);
    reprise_converter_destroy(taken);
    CHECK(reprise_abi_version() == REPRISE_ABI_VERSION, "library ABI %x", reprise_abi_version());
}

/* Each bad argument is an error naming it, never a crash. */
static void test_bad_arguments(void) {
    static float rgba[H * W * 4], depth[H * W];
    reprise_converter* converter = NULL;
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, NULL, &converter), REPRISE_OK);
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, NULL, NULL),
                  REPRISE_ERROR_INVALID_ARGUMENT);
    reprise_converter_options options;
    reprise_converter_options_init(&options, sizeof options);
    options.factor = 0;
    reprise_converter* bad = NULL;
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, &options, &bad),
                  REPRISE_ERROR_INVALID_ARGUMENT);
    CHECK(bad == NULL && strstr(reprise_last_error(), "options->factor 0") != NULL, "message: %s",
          reprise_last_error());
    EXPECT_STATUS(reprise_converter_send(NULL, NULL), REPRISE_ERROR_INVALID_ARGUMENT);
    EXPECT_STATUS(reprise_converter_send(converter, NULL), REPRISE_ERROR_INVALID_ARGUMENT);

    struct {
        const char* what;
        const char* field; /* the message must name it */
        int64_t color_stride;
        reprise_format color_format;
        int depth_width;
        float projection0;
        int null_color;
    } cases[] = {
        {"stride too small", "frame->color.stride", W * 16 - 1, REPRISE_FORMAT_RGBA32_FLOAT, W,
         1.0f, 0},
        {"negative stride", "frame->color.stride", -W * 16, REPRISE_FORMAT_RGBA32_FLOAT, W, 1.0f,
         0},
        {"unknown format", "frame->color.format 77", W * 16, 77, W, 1.0f, 0},
        {"integer colour", "frame->color.format", W * 16, REPRISE_FORMAT_R32_UINT, W, 1.0f, 0},
        {"depth of another size", "frame->depth is 63x48", W * 16, REPRISE_FORMAT_RGBA32_FLOAT,
         W - 1, 1.0f, 0},
        {"NaN in the projection", "frame->camera.projection[0]", W * 16,
         REPRISE_FORMAT_RGBA32_FLOAT, W, NAN, 0},
        {"no colour", "frame->color.data is NULL", W * 16, REPRISE_FORMAT_RGBA32_FLOAT, W, 1.0f, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        reprise_gbuffer frame;
        reprise_gbuffer_init(&frame, sizeof frame);
        frame.color =
            image(cases[i].null_color ? NULL : rgba, cases[i].color_stride, cases[i].color_format);
        frame.depth = image(depth, W * 4, REPRISE_FORMAT_R32_FLOAT);
        frame.depth.width = cases[i].depth_width;
        frame.camera.valid = 1;
        frame.camera.projection[0] = cases[i].projection0;
        frame.camera.near_plane = 0.1f;
        frame.camera.far_plane = 10.0f;
        EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_ERROR_INVALID_ARGUMENT);
        CHECK(strstr(reprise_last_error(), cases[i].field) != NULL, "%s: message '%s' lacks '%s'",
              cases[i].what, reprise_last_error(), cases[i].field);
    }
    /* A reset that is none of REPRISE_RESET_*. */
    reprise_gbuffer frame;
    reprise_gbuffer_init(&frame, sizeof frame);
    frame.color = image(rgba, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    frame.reset = 3;
    EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(reprise_last_error(), "frame->reset 3") != NULL, "message: %s",
          reprise_last_error());
    /* A G-buffer from another reprise.h. */
    reprise_gbuffer_init(&frame, sizeof frame);
    frame.struct_size = 12;
    EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_ERROR_ABI_MISMATCH);
    /* An output with a channel the converter does not make. */
    reprise_gbuffer_init(&frame, sizeof frame);
    frame.color = image(rgba, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_OK);
    reprise_gbuffer out;
    reprise_gbuffer_init(&out, sizeof out);
    out.color = image(rgba, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    out.id = image(depth, W * 4, REPRISE_FORMAT_R32_UINT);
    EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(reprise_last_error(), "out->id") != NULL, "message: %s", reprise_last_error());
    out.id.data = NULL;
    out.color.width = W / 2; /* the output is kept after an error: asked again, right size */
    EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_ERROR_INVALID_ARGUMENT);
    out.color.width = W;
    EXPECT_STATUS(reprise_converter_receive(converter, &out), REPRISE_OK);
    CHECK(strcmp(reprise_last_error(), "") == 0, "no error left after a success: %s",
          reprise_last_error());
    EXPECT_STATUS(reprise_decoder_send_packet(NULL, NULL, 0), REPRISE_ERROR_INVALID_ARGUMENT);
    CHECK(
        strcmp(reprise_status_name(REPRISE_ERROR_ABI_MISMATCH), "REPRISE_ERROR_ABI_MISMATCH") == 0,
        "status name");
    reprise_converter_destroy(converter);
    reprise_converter_destroy(NULL);
}

/* A frame that needs more than the memory limit is refused with the figure, naming the setter. */
static void test_memory_limit(void) {
    static float rgba[H * W * 4];
    const uint64_t limit = reprise_max_memory();
    CHECK(limit == ((uint64_t)4 << 30), "default limit %llu bytes", (unsigned long long)limit);
    EXPECT_STATUS(reprise_set_max_memory(0), REPRISE_ERROR_INVALID_ARGUMENT);
    reprise_converter* converter = NULL;
    EXPECT_STATUS(reprise_converter_create(REPRISE_ABI_VERSION, NULL, &converter), REPRISE_OK);
    EXPECT_STATUS(reprise_set_max_memory(64 * 1024), REPRISE_OK);
    reprise_gbuffer frame;
    reprise_gbuffer_init(&frame, sizeof frame);
    frame.color = image(rgba, W * 16, REPRISE_FORMAT_RGBA32_FLOAT);
    EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_ERROR_INVALID_ARGUMENT);
    printf("memory: 64 KiB limit: %s\n", reprise_last_error());
    CHECK(strstr(reprise_last_error(), "reprise_set_max_memory to change") != NULL, "message: %s",
          reprise_last_error());
    EXPECT_STATUS(reprise_set_max_memory(limit), REPRISE_OK);
    EXPECT_STATUS(reprise_converter_send(converter, &frame), REPRISE_OK);
    reprise_converter_destroy(converter);
}

/* A failed call on another thread leaves this thread's message alone; both threads run their
 * own converter at the same time. */
static void* fail_and_convert(void* result) {
    reprise_converter_send(NULL, NULL);
    *(double*)result = in_between_after(1);
    if (reprise_last_error()[0] != '\0') *(double*)result = -1.0; /* it succeeded last */
    return NULL;
}

static void test_threads(void) {
    reprise_decoder_send_packet(NULL, NULL, 0);
    char before[256];
    snprintf(before, sizeof before, "%s", reprise_last_error());
    double other = 0.0;
    pthread_t thread;
    CHECK(pthread_create(&thread, NULL, fail_and_convert, &other) == 0, "thread");
    const double here = in_between_after(1);
    reprise_decoder_send_packet(NULL, NULL, 0);
    pthread_join(thread, NULL);
    printf("threads: two converters at once: %.2f and %.2f dB\n", here, other);
    CHECK(here > 60.0 && other > 60.0, "concurrent converters: %.2f, %.2f dB", here, other);
    CHECK(strcmp(reprise_last_error(), before) == 0 && strstr(before, "decoder is NULL") != NULL,
          "this thread's message '%s', was '%s'", reprise_last_error(), before);
}

int main(void) {
    test_converter_pan();
    test_converter_reset();
    test_stereo_plane();
    test_codec_round_trip();
    test_abi_mismatch();
    test_bad_arguments();
    test_memory_limit();
    test_threads();
    if (failures)
        fprintf(stderr, "test_capi: %d checks failed\n", failures);
    else
        printf("test_capi: all checks passed\n");
    return failures ? 1 : 0;
}
