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
