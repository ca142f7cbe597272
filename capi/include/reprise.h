/* reprise.h: the stable C interface of reprise (C99; docs/c_api.md).
 *
 * Opaque handles: reprise_converter (frame-rate upconversion), reprise_stereo (the second eye
 * from one eye), reprise_encoder / reprise_decoder (the scene-aware codec). Inputs are described
 * by reprise_gbuffer (every channel with its size, row stride in bytes and pixel format, plus the
 * camera); outputs are written into caller-owned buffers described the same way.
 *
 * Conventions (docs/conventions.md): pixel origin top-left, +y down, pixel centres at +0.5.
 * Colour is linear-light RGB. Depth is linear view depth: the positive distance along the
 * viewing axis in scene units, background +inf. Motion is backward, in pixels: for the pixel
 * centre p, p + motion is where the same surface point was in the previous frame (content moving
 * right has negative x motion). Normals are world-space unit vectors, ids uint32 (0 background).
 * Cameras follow OpenGL: the camera looks down -Z, clip w = -z_view.
 *
 * Every function (but the destroys) returns a reprise_status; on an error reprise_last_error()
 * gives one message naming the function, the field and the problem. No function throws, aborts
 * on bad input or keeps a pointer it was given past the call.
 *
 * Threads: different handles may be used at the same time from different threads; one handle
 * from one thread at a time. The last-error message is per thread.
 */
#ifndef REPRISE_H
#define REPRISE_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(REPRISE_CAPI_BUILD)
#define REPRISE_API __attribute__((visibility("default")))
#else
#define REPRISE_API
#endif

/* The ABI version: a new major breaks callers built against an older one (a struct or a
 * function changed); a new minor only adds (fields at the end of structs, functions). Every
 * create takes the caller's REPRISE_ABI_VERSION: the major must equal the library's and the
 * minor be at most the library's. A struct_size of an older minor's struct is taken: the fields
 * it lacks keep their defaults. libreprise.so's SONAME carries the major. */
#define REPRISE_ABI_VERSION_MAJOR 1
#define REPRISE_ABI_VERSION_MINOR 4
#define REPRISE_ABI_VERSION \
    ((uint32_t)((REPRISE_ABI_VERSION_MAJOR << 16) | REPRISE_ABI_VERSION_MINOR))

typedef int32_t reprise_status;
enum {
    REPRISE_OK = 0,
    REPRISE_NEED_MORE = 1, /* nothing to receive yet: send the next input */
    REPRISE_ERROR_INVALID_ARGUMENT = -1,
    REPRISE_ERROR_ABI_MISMATCH = -2,     /* abi_version or a struct_size the library cannot take */
    REPRISE_ERROR_BUFFER_TOO_SMALL = -3, /* the result is kept: call again with a larger buffer */
    REPRISE_ERROR_INVALID_DATA = -4,     /* a bad packet; the decoder stays usable */
    REPRISE_ERROR_OUT_OF_MEMORY = -5,
    REPRISE_ERROR_INTERNAL = -6
};

/* The library's REPRISE_ABI_VERSION. */
REPRISE_API uint32_t reprise_abi_version(void);
/* "REPRISE_OK", "REPRISE_ERROR_INVALID_ARGUMENT", ...; "unknown status" for others. */
REPRISE_API const char* reprise_status_name(reprise_status status);
/* The message of the last call on this thread that returned an error ("" after a call that
 * did not). Thread-local: valid until the next reprise_* call on the same thread. */
REPRISE_API const char* reprise_last_error(void);

/* What one call may allocate, in bytes (default 4 GiB; docs/memory.md): a call that would need
 * more refuses with REPRISE_ERROR_INVALID_ARGUMENT and the figure. Process-wide, thread-safe,
 * for calls that start afterwards; bytes > 0. */
REPRISE_API reprise_status reprise_set_max_memory(uint64_t bytes);
REPRISE_API uint64_t reprise_max_memory(void);

/* Pixel formats: components of 32-bit float, 16-bit float (IEEE half) or 32-bit unsigned; and
 * (ABI 1.4) 8-bit sRGB display values, RGBA, for the codec's colour only: an engine's swapchain
 * image into the encoder (alpha not read), a client's texture out of a decoder made with
 * options.display (alpha 255 on surfaces, 0 on background). */
typedef int32_t reprise_format;
enum {
    REPRISE_FORMAT_NONE = 0,
    REPRISE_FORMAT_R32_FLOAT = 1,
    REPRISE_FORMAT_RG32_FLOAT = 2,
    REPRISE_FORMAT_RGB32_FLOAT = 3,
    REPRISE_FORMAT_RGBA32_FLOAT = 4,
    REPRISE_FORMAT_R16_FLOAT = 5,
    REPRISE_FORMAT_RG16_FLOAT = 6,
    REPRISE_FORMAT_RGB16_FLOAT = 7,
    REPRISE_FORMAT_RGBA16_FLOAT = 8,
    REPRISE_FORMAT_R32_UINT = 9,
    REPRISE_FORMAT_RGBA8_SRGB = 10
};

/* One channel: a non-owning view. data NULL = the channel is absent. Rows run top to bottom,
 * `stride` bytes apart (at least width x the pixel's bytes); no alignment is required. */
typedef struct reprise_image {
    void* data;
    int32_t width, height; /* pixels, 1..16384 */
    int64_t stride;        /* bytes from one row to the next */
    reprise_format format;
    int32_t reserved; /* 0 */
} reprise_image;

/* The camera of one instant. Matrices are column-major as OpenGL and GLM store them: element
 * (row r, column c) at [c * 4 + r]. */
typedef struct reprise_camera {
    double time;          /* seconds on the animation timeline */
    float view[16];       /* world -> camera */
    float projection[16]; /* camera -> clip, without jitter */
    float prev_view[16];  /* the previous frame's pair */
    float prev_projection[16];
    float jitter[2];             /* sub-pixel offset of the rendered samples, pixels */
    float near_plane, far_plane; /* scene units; far may be +inf */
    int32_t valid;               /* 0: no camera (render passes without one, video): ignored */
    int32_t reserved;            /* 0 */
} reprise_camera;

/* Whether a cut (a jump of the camera) lies between the previous frame and this one. A renderer
 * knows: YES drops everything before the frame (history, prediction), NO spares the test of the
 * pixels, UNKNOWN (0, what reprise_gbuffer_init sets) has the library test them. NO: ABI 1.1. */
typedef int32_t reprise_reset;
enum { REPRISE_RESET_UNKNOWN = 0, REPRISE_RESET_YES = 1, REPRISE_RESET_NO = 2 };

/* A rendered instant (input) or a made one (output): which channels each call reads or writes
 * is in its comment. Fill it with reprise_gbuffer_init (all absent, no camera), then set
 * channels. */
typedef struct reprise_gbuffer {
    uint32_t struct_size; /* sizeof(reprise_gbuffer) */
    int32_t reset;        /* REPRISE_RESET_*: whether a cut came before this frame */
    reprise_image color;  /* linear-light RGB(A), 32/16 float; A = coverage, 1 if absent */
    reprise_image depth;  /* linear view depth, scene units, background +inf: R32/R16 float */
    reprise_image motion; /* backward motion, pixels: RG32/RG16 float */
    reprise_image normal; /* world-space unit normal: RGB32/RGB16 float */
    reprise_image id;     /* object id, 0 = background: R32 uint */
    reprise_image ui;     /* UI layer, premultiplied linear RGBA, never warped: RGBA32/RGBA16 */
    reprise_camera camera;
    double fps; /* frame rate of the sequence, 0 = unknown */
} reprise_gbuffer;

REPRISE_API reprise_status reprise_gbuffer_init(reprise_gbuffer* gbuffer, size_t struct_size);

/* ---- frame-rate converter: `factor` output frames per input frame ---- */
typedef struct reprise_converter reprise_converter;

typedef int32_t reprise_fruc_mode;
enum { REPRISE_FRUC_INTERPOLATE = 0, REPRISE_FRUC_EXTRAPOLATE = 1 };
typedef int32_t reprise_warp;
enum {
    REPRISE_WARP_GRID = 0,
    REPRISE_WARP_REVERSE = 1,
    REPRISE_WARP_SPLAT = 2,
    REPRISE_WARP_AUTO = 3
};
typedef int32_t reprise_fill;
enum {
    REPRISE_FILL_PULLPUSH = 0,
    REPRISE_FILL_NONE = 1,
    REPRISE_FILL_ANDREEV = 2,
    REPRISE_FILL_AUTO = 3,
    REPRISE_FILL_PATCH = 4 /* frequency-selective reconstruction; not with REPRISE_WARP_AUTO */
};

typedef struct reprise_converter_options {
    uint32_t struct_size;      /* sizeof(reprise_converter_options) */
    int32_t factor;            /* 2..16 (default 2) */
    reprise_fruc_mode mode;    /* default interpolate (one input frame of latency) */
    reprise_warp warp;         /* default grid */
    reprise_fill fill;         /* default pull-push */
    int32_t refine;            /* optical-flow refinement of interpolation: 1 on (default), 0 off */
    float budget_db;           /* warp or fill auto: PSNR to reach, 0 = relative (default) */
    int32_t composite_ui;      /* 1: draw the UI layer into every output's colour (default 0) */
    int32_t widen_silhouettes; /* 1: edge pixels go with the nearer surface (default); minor 2 */
    int32_t perceptual;        /* 1: colour warped and blended as the square root of linear light
                                  (default), 0: in linear light; minor 3 */
} reprise_converter_options;

/* Sets the defaults above and struct_size. */
REPRISE_API reprise_status reprise_converter_options_init(reprise_converter_options* options,
                                                          size_t struct_size);
REPRISE_API reprise_status reprise_converter_create(uint32_t abi_version,
                                                    const reprise_converter_options* options,
                                                    reprise_converter** converter);
REPRISE_API void reprise_converter_destroy(reprise_converter* converter);
/* Reads colour (required), depth, motion, ui, the camera, fps and reset. Outputs then come out
 * of receive in order: interpolation gives, from the second frame on, factor - 1 frames between
 * it and its predecessor followed by the frame itself; extrapolation the frame itself followed
 * by factor - 1 frames beyond it. */
REPRISE_API reprise_status reprise_converter_send(reprise_converter* converter,
                                                  const reprise_gbuffer* frame);
/* End of the sequence: the outputs still to receive stay; the next frame sent starts anew. */
REPRISE_API reprise_status reprise_converter_flush(reprise_converter* converter);
/* The size of the next output: REPRISE_OK, or REPRISE_NEED_MORE when there is none. */
REPRISE_API reprise_status reprise_converter_output_size(reprise_converter* converter,
                                                         int32_t* width, int32_t* height);
/* Writes the next output into `out`: colour required, depth, motion and ui where data is set
 * (each of the output size); normal and id must be absent. Sets camera and fps. NEED_MORE when
 * there is none; on an error the output is kept for the next call. */
REPRISE_API reprise_status reprise_converter_receive(reprise_converter* converter,
                                                     reprise_gbuffer* out);

/* ---- stereo: the second eye from one rendered eye ---- */
typedef struct reprise_stereo reprise_stereo;

typedef int32_t reprise_rig;
enum { REPRISE_RIG_PARALLEL = 0, REPRISE_RIG_OFF_AXIS = 1 };
typedef int32_t reprise_eye;
enum { REPRISE_EYE_LEFT = 0, REPRISE_EYE_RIGHT = 1 };

typedef struct reprise_stereo_options {
    uint32_t struct_size;      /* sizeof(reprise_stereo_options) */
    float ipd;                 /* eye separation, scene units (default 0.064) */
    float convergence;         /* zero-disparity distance of the off-axis rig (default 10) */
    reprise_rig rig;           /* default parallel */
    reprise_eye rendered_eye;  /* the eye the input is (default left): the other is made */
    reprise_warp warp;         /* grid (default) or splat */
    reprise_fill fill;         /* pull-push (default), none, Andreev or patch (not auto) */
    int32_t temporal;          /* 1: the previous rendered frame fills holes first (default 0) */
    int32_t widen_silhouettes; /* 1: edge pixels go with the nearer surface (default); minor 2 */
    int32_t perceptual;        /* 1: colour warped and filled as the square root of linear light
                                  (default), 0: in linear light; minor 3 */
} reprise_stereo_options;

REPRISE_API reprise_status reprise_stereo_options_init(reprise_stereo_options* options,
                                                       size_t struct_size);
REPRISE_API reprise_status reprise_stereo_create(uint32_t abi_version,
                                                 const reprise_stereo_options* options,
                                                 reprise_stereo** stereo);
REPRISE_API void reprise_stereo_destroy(reprise_stereo* stereo);
/* Makes the other eye of `rendered` (colour, depth and a valid camera required; reset drops the
 * temporal history) into `eye`: colour required, depth where data is set, both of the rendered
 * size. Sets eye->camera to the made eye's camera. */
REPRISE_API reprise_status reprise_stereo_synthesize(reprise_stereo* stereo,
                                                     const reprise_gbuffer* rendered,
                                                     reprise_gbuffer* eye);

/* ---- codec: bitstream in docs/bitstream.md ---- */
typedef struct reprise_encoder reprise_encoder;
typedef struct reprise_decoder reprise_decoder;

typedef int32_t reprise_depth_coding;
enum {
    REPRISE_DEPTH_LOSSLESS = 0, /* bit-exact float depth */
    REPRISE_DEPTH_BOUNDED = 1,  /* relative error at most depth_error */
    REPRISE_DEPTH_NONE = 2,     /* no depth: motion sent whole */
    REPRISE_DEPTH_VIEW = 3      /* reprojection error at most view_error_px */
};

typedef struct reprise_encoder_options {
    uint32_t struct_size;       /* sizeof(reprise_encoder_options) */
    int32_t qp;                 /* quantiser 0 (finest) .. 51 (default 28) */
    int32_t bitrate_kbps;       /* > 0: rate control to this bitrate (default 0: constant qp) */
    int32_t keyint;             /* key frame at least every keyint frames (default 0: on cuts) */
    double fps;                 /* when the frames carry none (default 30) */
    int32_t chroma444;          /* 1: 4:4:4, 0: 4:2:0 (default) */
    reprise_depth_coding depth; /* default lossless */
    float depth_error;          /* REPRISE_DEPTH_BOUNDED (default 1e-4) */
    float view_error_px;        /* REPRISE_DEPTH_VIEW, pixels (default 0.25) */
    float view_displacement;    /* REPRISE_DEPTH_VIEW, scene units (default 0.164) */
    float motion_error_px;      /* 0 = every pixel to 1/8 px, else 0.1..8 (default 0.25) */
    int32_t skip_threshold;     /* 8-bit display levels a skipped block may miss by (default 2) */
    int32_t detect_cuts;        /* 1 (default): key frame when prediction misses most pixels */
    int32_t fit_cameras;        /* 1 (default): frames without a camera get a fitted one */
    int32_t fixed_bounds;       /* 1: view and motion bounds as given at every qp; 0 (default):
                                   above qp 34 both double every 6 qp (was `reserved`, 0) */
} reprise_encoder_options;

REPRISE_API reprise_status reprise_encoder_options_init(reprise_encoder_options* options,
                                                        size_t struct_size);
REPRISE_API reprise_status reprise_encoder_create(uint32_t abi_version,
                                                  const reprise_encoder_options* options,
                                                  reprise_encoder** encoder);
REPRISE_API void reprise_encoder_destroy(reprise_encoder* encoder);
/* Encodes one frame: colour required (linear float, or REPRISE_FORMAT_RGBA8_SRGB display values,
 * coded as they are); depth, motion and the camera enable prediction; reset forces a key frame.
 * Its packet then comes out of receive_packet. */
REPRISE_API reprise_status reprise_encoder_send_frame(reprise_encoder* encoder,
                                                      const reprise_gbuffer* frame);
/* Copies the next packet into data[0..capacity) and sets *size to its length. NEED_MORE when
 * there is none; REPRISE_ERROR_BUFFER_TOO_SMALL (with *size set; data may be NULL) keeps it. */
REPRISE_API reprise_status reprise_encoder_receive_packet(reprise_encoder* encoder, uint8_t* data,
                                                          size_t capacity, size_t* size);
REPRISE_API reprise_status reprise_encoder_flush(reprise_encoder* encoder);

typedef struct reprise_decoder_options {
    uint32_t struct_size; /* sizeof(reprise_decoder_options) */
    int32_t display;      /* 1: colour comes out as REPRISE_FORMAT_RGBA8_SRGB display values (the
                             stream's own, no conversion); 0 (default): linear float. ABI 1.4,
                             was `reserved`, 0 */
    int64_t max_pixels;   /* larger key frames are refused (default 8192 x 4320) */
} reprise_decoder_options;

REPRISE_API reprise_status reprise_decoder_options_init(reprise_decoder_options* options,
                                                        size_t struct_size);
REPRISE_API reprise_status reprise_decoder_create(uint32_t abi_version,
                                                  const reprise_decoder_options* options,
                                                  reprise_decoder** decoder);
REPRISE_API void reprise_decoder_destroy(reprise_decoder* decoder);
/* Takes one whole packet. A bad one is REPRISE_ERROR_INVALID_DATA naming the field; the decoder
 * stays usable and resumes at the next decodable frame. */
REPRISE_API reprise_status reprise_decoder_send_packet(reprise_decoder* decoder,
                                                       const uint8_t* data, size_t size);
REPRISE_API reprise_status reprise_decoder_flush(reprise_decoder* decoder);
/* As the converter's: the next frame's size, or NEED_MORE. */
REPRISE_API reprise_status reprise_decoder_output_size(reprise_decoder* decoder, int32_t* width,
                                                       int32_t* height);
/* Writes the next decoded frame: colour required (a float format, or REPRISE_FORMAT_RGBA8_SRGB
 * from a decoder made with options.display), depth and motion where data is set; normal, id and
 * ui must be absent. Sets camera and fps. */
REPRISE_API reprise_status reprise_decoder_receive_frame(reprise_decoder* decoder,
                                                         reprise_gbuffer* out);

#ifdef __cplusplus
}
#endif

#endif /* REPRISE_H */
