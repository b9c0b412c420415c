// Result types used everywhere below the plugin: no exceptions cross a module boundary.
#pragma once

#include <optional>
#include <string>
#include <utility>

namespace gust {

/// Success, or failure with a human-readable message. Cheap to copy on success.
class Status {
  public:
    Status() = default;
    /// A failed status carrying `message` (the message should name the input and the reason).
    static Status failure(std::string message) {
        Status s;
        s.failed_ = true;
        s.message_ = std::move(message);
        return s;
    }
    bool ok() const { return !failed_; }
    explicit operator bool() const { return ok(); }
    /// Empty on success.
    const std::string& message() const { return message_; }

  private:
    bool failed_ = false;
    std::string message_;
};

/// A value of type T, or a failure message.
template <class T> class Result {
  public:
    Result(T value) : value_(std::move(value)) {}
    Result(Status status) : status_(std::move(status)) {}
    static Result failure(std::string message) { return Result(Status::failure(std::move(message))); }

    bool ok() const { return value_.has_value(); }
    explicit operator bool() const { return ok(); }
    const std::string& message() const { return status_.message(); }
    const Status& status() const { return status_; }
    T& value() { return *value_; }
    const T& value() const { return *value_; }
    T* operator->() { return &*value_; }
    const T* operator->() const { return &*value_; }
    T& operator*() { return *value_; }
    const T& operator*() const { return *value_; }

  private:
    std::optional<T> value_;
    Status status_;
};

} // namespace gust
