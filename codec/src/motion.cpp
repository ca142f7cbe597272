// Motion: what the two cameras explain is derived from decoded depth on both sides; only the
// difference (moving, skinned, morphed objects) is sent, quantised to 1/8 pixel, per 8x8 block
// flagged, so a still world under a moving camera sends a single flag.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "internal.hpp"
#include "kernels.hpp"
#include "slices.hpp"

namespace reprise::codec {

namespace {

constexpr int kBlock = 8;
constexpr uint8_t kNoResidual = 1;
constexpr uint8_t kPredictedObjects = 2;   // a varint follows: the objects that predict the base
constexpr int64_t kMaxResidual = 1 << 24;  // eighths of a pixel: 2 million pixels

using Residual = MotionResidual;

inline bool finite(glm::vec2 v) { return std::isfinite(v.x) && std::isfinite(v.y); }

inline glm::vec2 usable_base(glm::vec2 base) { return finite(base) ? base : glm::vec2(0.0f); }

Residual residual_of(glm::vec2 source, glm::vec2 base) {
    Residual r;
    if (!finite(source)) {
        r.invalid = finite(base);  // NaN both ways needs nothing
        return r;
    }
    const glm::vec2 d = (source - usable_base(base)) * 8.0f;
    // Rounded half up without a library call (only the encoder rounds: any rounding is valid).
    auto q = [](float v) {
        v = std::clamp(v, -float(kMaxResidual), float(kMaxResidual)) + 0.5f;
        const int32_t t = int32_t(v);
        return t - int32_t(v < float(t));
    };
    r.x = q(d.x);
    r.y = q(d.y);
    return r;
}

glm::vec2 apply(glm::vec2 base, const Residual& r) {
    if (r.invalid) return glm::vec2(std::numeric_limits<float>::quiet_NaN());
    if (r.x == 0 && r.y == 0) return base;
    return usable_base(base) + glm::vec2(float(r.x), float(r.y)) * 0.125f;
}

struct Models {
    BitModel block[2];
    BitModel nonzero[3];
    BitModel invalid;
    IntModel<20> component[2];
};

struct SliceJob {
    int width, y0, y1;
    ImageView<const glm::vec2> base;
    ImageView<const glm::vec2> source;  // encoder only: the renderer's motion
    ImageView<glm::vec2> out;
    Residual* residuals;  // per pixel of the frame, for contexts and prediction
    const ModelCarry* carry;
    int slice;
    std::size_t pixels = 0;
    StreamStats::MotionBits bits;  // encoder

    const Residual* at(int x, int y) const {
        return x >= 0 && y >= y0 ? &residuals[std::size_t(y) * width + x] : nullptr;
    }
};

inline int nonzero_context(const SliceJob& j, int x, int y) {
    const Residual *left = j.at(x - 1, y), *top = j.at(x, y - 1);
    return (left && !left->zero()) + (top && !top->zero());
}

// Moving objects have nearly the same residual as their neighbours: predict from the left one,
// else the top one.
inline Residual neighbour_prediction(const SliceJob& j, int x, int y) {
    const Residual *left = j.at(x - 1, y), *top = j.at(x, y - 1);
    if (left && !left->zero() && !left->invalid) return *left;
    if (top && !top->zero() && !top->invalid) return *top;
    return {};
}

}  // namespace

bool motion_residual_row_reference(const MotionResidualRow& r, int x_begin, int x_end) {
    for (int x = x_begin; x < x_end; ++x)
        if (!residual_of(r.source[x], r.base[x]).zero()) return true;
    return false;
}

namespace {

template <bool Encode, class Coder>
bool code_slice(SliceJob& j, Coder& rc) {
    Models m;
    j.carry->load(j.slice, m);
    std::vector<uint8_t> block_nonzero;
    int previous_block = 0;
    for (int by = j.y0; by < j.y1; by += kBlock) {
        const int bh = std::min(kBlock, j.y1 - by);
        const int blocks = (j.width + kBlock - 1) / kBlock;
        block_nonzero.assign(blocks, 0);
        for (int b = 0; b < blocks; ++b) {
            if constexpr (Encode) {
                rc.tally_into(&j.bits.tree);
                for (int y = by; y < by + bh && !block_nonzero[b]; ++y)
                    for (int x = b * kBlock; x < std::min(j.width, (b + 1) * kBlock); ++x)
                        if (!residual_of(j.source(x, y), j.base(x, y)).zero()) block_nonzero[b] = 1;
                rc.bit(m.block[previous_block], block_nonzero[b]);
            } else {
                block_nonzero[b] = uint8_t(rc.bit(m.block[previous_block]));
            }
            previous_block = block_nonzero[b];
        }
        for (int y = by; y < by + bh; ++y)
            for (int x = 0; x < j.width; ++x) {
                Residual r;
                if (block_nonzero[x / kBlock]) {
                    BitModel& nz = m.nonzero[nonzero_context(j, x, y)];
                    if constexpr (Encode) {
                        r = residual_of(j.source(x, y), j.base(x, y));
                        rc.tally_into(&j.bits.pixels);
                        rc.bit(nz, !r.zero());
                        if (!r.zero()) {
                            rc.bit(m.invalid, r.invalid);
                            if (!r.invalid) {
                                const Residual p = neighbour_prediction(j, x, y);
                                encode_int(rc, m.component[0], int64_t(r.x) - p.x);
                                encode_int(rc, m.component[1], int64_t(r.y) - p.y);
                            }
                        }
                    } else if (rc.bit(nz)) {
                        r.invalid = rc.bit(m.invalid);
                        if (!r.invalid) {
                            int64_t vx = 0, vy = 0;
                            if (!decode_int(rc, m.component[0], vx) ||
                                !decode_int(rc, m.component[1], vy))
                                return false;
                            const Residual p = neighbour_prediction(j, x, y);
                            vx += p.x;
                            vy += p.y;
                            if (std::abs(vx) > kMaxResidual || std::abs(vy) > kMaxResidual)
                                return false;
                            r.x = int32_t(vx);
                            r.y = int32_t(vy);
                        }
                    }
                }
                j.residuals[std::size_t(y) * j.width + x] = r;
                j.pixels += !r.zero();
                j.out(x, y) = apply(j.base(x, y), r);
            }
        if constexpr (!Encode) {
            if (rc.overrun() > 8) return false;
        }
    }
    j.carry->save(j.slice, m);
    return true;
}

// Motion the cameras explain (to the previous frame as this frame's camera records it).
// A frame's owners before its motion models set them: 0 everywhere, in the buffer the picture
// held before (a fresh one each frame cost its page faults).
void clear_owners(Image<uint32_t>& owner, int w, int h) {
    ensure_size(owner, w, h);
    std::fill(owner.data(), owner.data() + owner.pixel_count(), 0u);
}

void base_motion(const Camera& camera, ImageView<const float> depth, int w, int h,
                 Image<glm::vec2>& base) {
    ensure_size(base, w, h);
    if (depth.empty()) {
        std::fill(base.data(), base.data() + base.pixel_count(), glm::vec2(0.0f));
        return;
    }
    camera_motion(camera, depth, camera.prev_view, camera.prev_projection, base.view());
}

// Whether this frame's object motions start at its reference: the frame before, with depth and
// each pixel's object.
bool objects_predictable(const FrameContext& fc, const Camera& camera) {
    const Picture* ref = fc.reference;
    return !fc.objects.empty() && !fc.key && ref && !ref->owner.empty() && !ref->depth.empty() &&
           camera.prev_view == ref->camera.view && camera.prev_projection == ref->camera.projection;
}

// The field of an object id (the last of them with it), looked up once per run of the id.
class FieldOf {
public:
    explicit FieldOf(const std::vector<ObjectField>& fields) : fields_(fields) {}
    const ObjectField* operator()(uint32_t id) {
        if (id != id_) {
            id_ = id, field_ = nullptr;
            for (const ObjectField& f : fields_)
                if (f.id == id) field_ = &f;
        }
        return field_;
    }

private:
    const std::vector<ObjectField>& fields_;
    uint32_t id_ = 0;
    const ObjectField* field_ = nullptr;
};

// Objects whose pixels are predicted from the reference (bit k: the object list's k-th):
// where a pixel is predicted to move with one of them (predict_owners), its base is that
// object's motion, and the cameras' motion joins the fields (id 0) over the box of those pixels
// so that a node can still choose it. Only with the frame before as the reference. The encoder
// (`source` given) keeps the objects whose motion holds, within the bound, on at least 3/4 of
// the pixels predicted to move with them. Returns the objects used.
uint32_t predict_from_objects(const FrameContext& fc, const Camera& camera, uint32_t objects,
                              Image<glm::vec2>& base, std::vector<ObjectField>& fields,
                              Image<uint32_t>& predicted, ImageView<const glm::vec2> source = {}) {
    predicted.clear();  // empty, its memory kept for the next frame
    if (!objects_predictable(fc, camera)) return 0;
    const int w = base.width(), h = base.height();
    ensure_size(predicted, w, h);
    const Picture& ref = *fc.reference;
    auto predict = [&] {
        return objects != 0 && predict_owners(fields, objects, ref.depth.view(), ref.owner.view(),
                                              predicted.view());
    };
    bool any = predict();
    if (any && !source.empty()) {
        std::vector<std::size_t> pixels(fields.size()), held(fields.size());
        FieldOf field_of(fields);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (const uint32_t id = predicted(x, y))
                    if (const ObjectField* f = field_of(id)) {
                        const std::size_t k = std::size_t(f - fields.data());
                        ++pixels[k];
                        const glm::vec2 d = f->at(x, y) - source(x, y);
                        held[k] += glm::dot(d, d) <= fc.sp->motion_error * fc.sp->motion_error;
                    }
        uint32_t kept = 0;
        for (std::size_t k = 0; k < fields.size(); ++k)
            if (pixels[k] > 0 && 4 * held[k] >= 3 * pixels[k]) kept |= 1u << k;
        if (kept != objects) objects = kept, any = predict();
    }
    if (!any) {
        predicted.clear();
        return 0;
    }
    int x0 = w, y0 = h, x1 = 0, y1 = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            if (predicted(x, y) != 0)
                x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1),
                y1 = std::max(y1, y + 1);
    ObjectField cameras = std::move(fc.work->cameras_field);
    cameras.id = 0, cameras.x0 = x0, cameras.y0 = y0;
    ensure_size(cameras.motion, x1 - x0, y1 - y0);
    FieldOf field_of(fields);
    for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
            cameras.motion(x - x0, y - y0) = base(x, y);
            if (const uint32_t id = predicted(x, y))
                if (const ObjectField* f = field_of(id)) base(x, y) = f->at(x, y);
        }
    fields.push_back(std::move(cameras));
    return objects;
}

// The objects' fields of this frame (object_fields); the cameras' field the last frame added
// (predict_from_objects) keeps its memory for this one's.
void frame_fields(const FrameContext& fc, const Camera& camera, ImageView<const float> depth) {
    std::vector<ObjectField>& fields = fc.work->object_fields;
    if (!fields.empty() && fields.back().id == 0) {
        fc.work->cameras_field = std::move(fields.back());
        fields.pop_back();
    }
    object_fields(camera, depth, fc.objects, fields);
}

std::vector<SliceJob> slice_jobs(const SequenceParams& sp, const Image<glm::vec2>& base,
                                 ImageView<const glm::vec2> source, Image<glm::vec2>& out,
                                 std::vector<Residual>& residuals, const ModelCarry& carry) {
    std::vector<SliceJob> jobs;
    for (int s = 0; s < sp.slices; ++s) {
        const int y0 = std::min(sp.height, sp.slice_begin(s) * kMb);
        const int y1 = std::min(sp.height, sp.slice_begin(s + 1) * kMb);
        jobs.push_back(
            {sp.width, y0, y1, base.view(), source, out.view(), residuals.data(), &carry, s});
    }
    return jobs;
}

}  // namespace

void encode_motion(const FrameContext& fc, const Camera& camera, ImageView<const float> depth,
                   ImageView<const glm::vec2> source, ImageView<const uint32_t> ids,
                   Image<glm::vec2>& out, Image<uint32_t>& owner, std::vector<uint8_t>& bytes,
                   StreamStats& stats) {
    const SequenceParams& sp = *fc.sp;
    const int w = sp.width, h = sp.height;
    const ModelCarry carry = fc.carry(&Picture::Models::motion);
    Image<glm::vec2>& base = fc.work->base_motion;
    base_motion(camera, depth, w, h, base);
    ensure_size(out, w, h);
    const std::size_t start = bytes.size();
    // Whether any pixel needs a residual; the slices recompute the residuals they code.
    const bool models = sp.motion_error > 0.0f;
    std::atomic<bool> any{false};
    if (!source.empty())
        parallel_for(0, h, [&](int y0, int y1) {
            for (int y = y0; y < y1 && !any.load(std::memory_order_relaxed); ++y)
                if (models
                        ? !motion_within_bound(source, base.view(), y, sp.motion_error)
                        : motion_residual_row({source.row(y), base.data() + std::size_t(y) * w, w}))
                    any.store(true, std::memory_order_relaxed);
        });
    ByteWriter wr(bytes);
    if (any && models && !fc.objects.empty())
        clear_owners(owner, w, h);
    else
        owner = {};
    if (!any) {
        wr.u8(kNoResidual);
        std::swap(out, base);  // the camera motion is the motion (base is remade every frame)
    } else if (models) {
        const bool objects = !fc.objects.empty();
        frame_fields(fc, camera, depth);
        const uint32_t all = uint32_t((uint64_t(1) << fc.objects.size()) - 1);
        const uint32_t predicting = predict_from_objects(
            fc, camera, all, base, fc.work->object_fields, fc.work->predicted_owner, source);
        wr.u8(predicting ? kPredictedObjects : 0);
        if (predicting) wr.varint(predicting);
        encode_motion_models(sp, depth, base.view(), source, ids, fc.work->object_fields,
                             fc.work->predicted_owner.view(), out.view(),
                             objects ? owner.view() : ImageView<uint32_t>{}, fc.work->motion_models,
                             carry, fc.work->slice_bytes, bytes, stats);
    } else {
        wr.u8(0);
        std::vector<Residual>& residuals = fc.work->motion_residuals;
        residuals.resize(std::size_t(w) * h);
        std::vector<SliceJob> jobs = slice_jobs(sp, base, source, out, residuals, carry);
        encode_slices(sp.slices, fc.work->slice_bytes, bytes, [&](int s, std::vector<uint8_t>& b) {
            RangeEncoder rc(b);
            code_slice<true>(jobs[s], rc);
            rc.finish();
        });
        for (const SliceJob& j : jobs) {
            stats.motion_residual_pixels += j.pixels;
            stats.motion_parts += j.bits;
        }
    }
    stats.motion_bits += 8 * (bytes.size() - start);
}

Status decode_motion(const FrameContext& fc, const Camera& camera, ImageView<const float> depth,
                     std::span<const uint8_t> in, Image<glm::vec2>& out, Image<uint32_t>& owner,
                     StreamStats& stats) {
    const SequenceParams& sp = *fc.sp;
    const int w = sp.width, h = sp.height;
    const ModelCarry carry = fc.carry(&Picture::Models::motion);
    Image<glm::vec2>& base = fc.work->base_motion;
    base_motion(camera, depth, w, h, base);
    ensure_size(out, w, h);
    ByteReader r(in, "motion section");
    const uint8_t flags = r.u8();
    if (!r.ok()) return Status::error(r.error());
    if (!(flags & kNoResidual) && sp.motion_error > 0.0f && !fc.objects.empty())
        clear_owners(owner, w, h);
    else
        owner = {};
    if (flags & ~(kNoResidual | kPredictedObjects) || flags == (kNoResidual | kPredictedObjects))
        return Status::error("motion section: unknown flags " + std::to_string(flags));
    uint32_t predicting = 0;
    if (flags & kPredictedObjects) {
        const uint64_t objects = r.varint();
        if (!r.ok()) return Status::error(r.error());
        if (objects == 0 || objects >> fc.objects.size() || sp.motion_error <= 0.0f ||
            !objects_predictable(fc, camera))
            return Status::error("motion section: objects " + std::to_string(objects) +
                                 " predict the base, but the frame has " +
                                 std::to_string(fc.objects.size()) +
                                 (objects_predictable(fc, camera)
                                      ? " objects"
                                      : " objects without the frame before as reference"));
        predicting = uint32_t(objects);
    }
    if (flags & kNoResidual) {
        if (r.remaining()) return Status::error("motion section: bytes after a no-residual flag");
        std::swap(out, base);  // the camera motion is the motion (base is remade every frame)
    } else {
        std::vector<std::span<const uint8_t>> slices;
        if (!read_slices(r, sp.slices, slices)) return Status::error(r.error());
        if (sp.motion_error > 0.0f) {
            const bool objects = !fc.objects.empty();
            frame_fields(fc, camera, depth);
            predict_from_objects(fc, camera, predicting, base, fc.work->object_fields,
                                 fc.work->predicted_owner);
            REPRISE_TRY(decode_motion_models(sp, depth, base.view(), fc.work->object_fields,
                                             fc.work->predicted_owner.view(), slices, out.view(),
                                             objects ? owner.view() : ImageView<uint32_t>{},
                                             fc.work->motion_models, carry, stats));
            stats.motion_bits += 8 * in.size();
            return {};
        }
        std::vector<Residual>& residuals = fc.work->motion_residuals;
        residuals.resize(std::size_t(w) * h);
        std::vector<SliceJob> jobs = slice_jobs(sp, base, {}, out, residuals, carry);
        REPRISE_TRY(
            decode_slices(slices, "motion section", [&](int s, std::span<const uint8_t> bytes) {
                RangeDecoder rc(bytes);
                return code_slice<false>(jobs[s], rc);
            }));
        for (const SliceJob& j : jobs) stats.motion_residual_pixels += j.pixels;
    }
    stats.motion_bits += 8 * in.size();
    return {};
}

}  // namespace reprise::codec
