#pragma once
// Failure reporting. Broken contracts in our own code are asserts (REPRISE_ASSERT);
// untrusted data (files, arguments, bitstreams) returns a Status naming what and where.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>

namespace reprise {

class [[nodiscard]] Status {
public:
    Status() = default;
    static Status error(std::string message) { return Status(std::move(message)); }

    bool ok() const { return message_.empty(); }
    explicit operator bool() const { return ok(); }
    const std::string& message() const { return message_; }

private:
    explicit Status(std::string message) : message_(std::move(message)) {
        if (message_.empty()) message_ = "unknown error";
    }
    std::string message_;
};

inline Status ok() { return {}; }

// The push/pull contract of the stages that take inputs and give outputs at their own pace
// (FrameRateConverter, Encoder, Decoder), as dav1d's send_data/get_picture: a push call (send_*)
// does the work and returns a Status, an error naming what was wrong (the stage stays usable);
// a pull call (receive_*) only hands over what is ready: Ok, the output is written, or
// NeedMoreData, nothing is ready (send the next input first).
class [[nodiscard]] Result {
public:
    enum Kind { Ok, NeedMoreData };
    Result(Kind kind) : kind_(kind) {}  // NOLINT: `return Result::Ok;`

    Kind kind() const { return kind_; }
    bool ok() const { return kind_ == Ok; }
    explicit operator bool() const { return ok(); }
    bool operator==(Kind kind) const { return kind_ == kind; }

private:
    Kind kind_;
};

}  // namespace reprise

#define REPRISE_ASSERT(expr)                                                                  \
    do {                                                                                      \
        if (!(expr)) {                                                                        \
            std::fprintf(stderr, "%s:%d: assertion failed: %s\n", __FILE__, __LINE__, #expr); \
            std::abort();                                                                     \
        }                                                                                     \
    } while (0)

// Returns from the calling function when a Status is an error.
#define REPRISE_TRY(expr)                   \
    do {                                    \
        ::reprise::Status status_ = (expr); \
        if (!status_.ok()) return status_;  \
    } while (0)
