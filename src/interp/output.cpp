#include "interp/output.hpp"

#include <stdexcept>

namespace trubal {

int TeeBuffer::overflow(int c) {
  if (c == traits_type::eof()) return traits_type::not_eof(c);
  if (copy_) copy_->sputc(static_cast<char>(c));
  return primary_->sputc(static_cast<char>(c));
}

std::streamsize TeeBuffer::xsputn(const char* s, std::streamsize n) {
  if (copy_) copy_->sputn(s, n);
  return primary_->sputn(s, n);
}

int TeeBuffer::sync() {
  if (copy_) copy_->pubsync();
  return primary_->pubsync();
}

Output::Output(std::ostream& out, std::ostream& err)
    : out_buf_(out.rdbuf()), err_buf_(err.rdbuf()), out_(&out_buf_), err_(&err_buf_) {}

void Output::set_log(const std::string& path) {
  out_.flush();
  err_.flush();
  out_buf_.set_copy(nullptr);
  err_buf_.set_copy(nullptr);
  log_.reset();
  log_path_.clear();
  if (path.empty()) return;
  auto file = std::make_unique<std::ofstream>(path, std::ios::app);
  if (!*file) throw std::runtime_error("cannot open the log file '" + path + "' for writing");
  log_ = std::move(file);
  log_path_ = path;
  out_buf_.set_copy(log_->rdbuf());
  err_buf_.set_copy(log_->rdbuf());
}

}  // namespace trubal
