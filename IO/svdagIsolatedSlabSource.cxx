#include "svdagIsolatedSlabSource.h"

#include "vtkErrorCode.h"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <new>
#include <type_traits>
#include <vector>

#ifndef _WIN32
#include <poll.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>
#define SVDAG_ISOLATE 1
#endif

static_assert(std::is_trivially_copyable<svdag::Geometry>::value, "Geometry crosses a socket");

namespace
{
// Every message from the child starts with a status byte. An error carries its vtkErrorCode
// and message, so the parent throws what an in-process source would have thrown. An Ok is
// followed by the source's warnings new since the last Ok (a count, then each as a length and
// its bytes), then by what was asked for.
enum Status : unsigned char
{
  Ok = 1,
  Error = 2
};

struct Request
{
  int32_t z0;
  int32_t nz;
};

#ifdef SVDAG_ISOLATE
// False when the peer closed its end or the socket failed. MSG_NOSIGNAL: a dead peer must
// not kill this process with SIGPIPE.
bool sendAll(int fd, const void* data, size_t size)
{
  const char* p = static_cast<const char*>(data);
  while (size > 0)
  {
    const ssize_t n = ::send(fd, p, size, MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return false;
    p += n;
    size -= size_t(n);
  }
  return true;
}

enum class Received
{
  All,    // exactly the bytes asked for
  Closed, // the peer closed its end (or the socket failed) first
  Silent  // nothing arrived for the timeout
};

// Reads exactly `size` bytes, waiting at most `timeoutSeconds` for each (a negative timeout
// waits forever).
Received receiveAll(int fd, void* data, size_t size, int timeoutSeconds)
{
  char* p = static_cast<char*>(data);
  while (size > 0)
  {
    if (timeoutSeconds >= 0)
    {
      pollfd pfd{ fd, POLLIN, 0 };
      const int ready = ::poll(&pfd, 1, timeoutSeconds * 1000);
      if (ready < 0 && errno == EINTR)
        continue;
      if (ready == 0)
        return Received::Silent;
    }
    const ssize_t n = ::recv(fd, p, size, 0);
    if (n < 0 && errno == EINTR)
      continue;
    if (n <= 0)
      return Received::Closed;
    p += n;
    size -= size_t(n);
  }
  return Received::All;
}

void sendError(int fd, unsigned long code, const std::string& message)
{
  const unsigned char status = Error;
  const uint64_t code64 = code;
  const uint64_t length = message.size();
  sendAll(fd, &status, 1) && sendAll(fd, &code64, sizeof code64) &&
    sendAll(fd, &length, sizeof length) && sendAll(fd, message.data(), message.size());
}

// Sends the warnings of `source` from the `sent`-th on.
bool sendWarnings(int fd, const svdagSlabSource& source, size_t& sent)
{
  const std::vector<std::string>& all = source.warnings();
  const uint64_t count = all.size() - sent;
  if (!sendAll(fd, &count, sizeof count))
    return false;
  for (; sent < all.size(); ++sent)
  {
    const uint64_t length = all[sent].size();
    if (!sendAll(fd, &length, sizeof length) || !sendAll(fd, all[sent].data(), all[sent].size()))
      return false;
  }
  return true;
}

// Runs `body`, reporting what it throws over `fd`. False if it threw.
template <typename Body>
bool reportingErrors(int fd, Body&& body)
{
  try
  {
    body();
    return true;
  }
  catch (const svdagReadError& e)
  {
    sendError(fd, e.code(), e.what());
  }
  catch (const std::bad_alloc&)
  {
    sendError(fd, vtkErrorCode::OutOfDiskSpaceError, "out of memory");
  }
  catch (const std::exception& e)
  {
    sendError(fd, vtkErrorCode::UnknownError, e.what());
  }
  return false;
}

[[noreturn]] void serve(int fd, const svdagIsolatedSlabSource::Opener& open)
{
  // A crash must end the child quietly: handlers inherited from the parent (Python's
  // faulthandler, a fuzzer's crash reporter) would report it as the parent's.
  for (int s : { SIGSEGV, SIGBUS, SIGFPE, SIGILL, SIGABRT })
    std::signal(s, SIG_DFL);
  std::unique_ptr<svdagSlabSource> source;
  if (!reportingErrors(fd, [&] { source = open(); }))
    _exit(0);
  const unsigned char ok = Ok;
  const svdag::Geometry geometry = source->geometry();
  const svdag::ScalarType type = source->scalarType();
  const svdagSampleKind kind = source->sampleKind();
  const size_t sampleSize = size_t(source->sampleSize());
  size_t warningsSent = 0;
  if (!sendAll(fd, &ok, 1) || !sendWarnings(fd, *source, warningsSent) ||
    !sendAll(fd, &geometry, sizeof geometry) || !sendAll(fd, &type, sizeof type) ||
    !sendAll(fd, &kind, sizeof kind))
    _exit(0);
  std::vector<char> slab;
  Request request{};
  while (receiveAll(fd, &request, sizeof request, -1) == Received::All)
  {
    const bool read = reportingErrors(fd, [&] {
      slab.resize(
        size_t(request.nz) * size_t(geometry.dims[0]) * size_t(geometry.dims[1]) * sampleSize);
      source->readSlab(request.z0, request.nz, slab.data());
    });
    if (read &&
      !(sendAll(fd, &ok, 1) && sendWarnings(fd, *source, warningsSent) &&
        sendAll(fd, slab.data(), slab.size())))
      break;
  }
  _exit(0);
}
#endif
}

struct svdagIsolatedSlabSource::Impl
{
  std::string fileName;
  std::string library; // "the HDF5 library", for messages
#ifdef SVDAG_ISOLATE
  int fd = -1;
  pid_t child = -1;

  // How the child ended, for the error message; reaps it.
  std::string childFate()
  {
    int status = 0;
    if (this->child > 0 && ::waitpid(this->child, &status, 0) == this->child)
    {
      this->child = -1;
      if (WIFSIGNALED(status))
        return "crashed (signal " + std::to_string(WTERMSIG(status)) + ", " +
          strsignal(WTERMSIG(status)) + ")";
      return "exited early (status " + std::to_string(WEXITSTATUS(status)) + ")";
    }
    return "stopped";
  }

  // Reads the child's status byte and, on an error, throws what the child threw; after an Ok,
  // appends the warnings that follow it to `warnings`.
  void receiveStatus(const std::string& what, std::vector<std::string>& warnings)
  {
    unsigned char status = 0;
    this->receive(&status, 1, what);
    if (status == Ok)
    {
      uint64_t count = 0;
      this->receive(&count, sizeof count, what);
      for (uint64_t i = 0; i < count; ++i)
        warnings.push_back(this->receiveText(what));
      return;
    }
    uint64_t code = 0;
    this->receive(&code, sizeof code, what);
    throw svdagReadError(code, this->receiveText(what));
  }

  // A length, then that many bytes (at most 1 MiB: the child's texts are messages).
  std::string receiveText(const std::string& what)
  {
    uint64_t length = 0;
    this->receive(&length, sizeof length, what);
    if (length > (1u << 20))
      throw svdagReadError(vtkErrorCode::FileFormatError,
        this->fileName + ": " + this->library + " sent a message of " + std::to_string(length) +
          " bytes while " + what);
    std::string text(size_t(length), '\0');
    this->receive(&text[0], text.size(), what);
    return text;
  }

  void receive(void* data, size_t size, const std::string& what)
  {
    const Received received = receiveAll(this->fd, data, size, SilenceTimeoutSeconds);
    if (received == Received::Silent)
    {
      ::kill(this->child, SIGKILL);
      this->childFate();
      throw svdagReadError(vtkErrorCode::FileFormatError,
        this->fileName + ": the reader sent nothing for " + std::to_string(SilenceTimeoutSeconds) +
          " s while " + what + " (a corrupt file that makes " + this->library + " loop?)");
    }
    if (received == Received::Closed)
      throw svdagReadError(vtkErrorCode::FileFormatError,
        this->fileName + ": " + this->library + " " + this->childFate() + " while " + what +
          " (corrupt file?)");
  }

  ~Impl()
  {
    // The child holds nothing worth finishing (it may be in the middle of a slab nobody will
    // read); ending it at once keeps a destructor from waiting for a long read.
    if (this->fd >= 0)
      ::close(this->fd);
    if (this->child > 0)
    {
      ::kill(this->child, SIGKILL);
      ::waitpid(this->child, nullptr, 0);
    }
  }
#else
  std::unique_ptr<svdagSlabSource> source;
#endif
};

svdagIsolatedSlabSource::svdagIsolatedSlabSource(
  const std::string& fileName, const char* formatName, Opener open)
  : impl(new Impl)
  , FormatName(formatName)
{
  impl->fileName = fileName;
  impl->library = std::string("the ") + formatName + " library";
#ifdef SVDAG_ISOLATE
  int fds[2] = { -1, -1 };
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0)
    throw svdagReadError(vtkErrorCode::CannotOpenFileError,
      fileName + ": cannot create a socket for the reader process: " + std::strerror(errno));
  const pid_t child = ::fork();
  if (child < 0)
  {
    ::close(fds[0]);
    ::close(fds[1]);
    throw svdagReadError(vtkErrorCode::CannotOpenFileError,
      fileName + ": cannot start the reader process: " + std::strerror(errno));
  }
  if (child == 0)
  {
    ::close(fds[0]);
    serve(fds[1], open);
  }
  ::close(fds[1]);
  impl->fd = fds[0];
  impl->child = child;
  impl->receiveStatus("opening it", this->Warnings);
  impl->receive(&this->Geometry, sizeof this->Geometry, "opening it");
  impl->receive(&this->Type, sizeof this->Type, "opening it");
  impl->receive(&this->Kind, sizeof this->Kind, "opening it");
#else
  impl->source = open();
  this->Geometry = impl->source->geometry();
  this->Type = impl->source->scalarType();
  this->Kind = impl->source->sampleKind();
  this->Warnings = impl->source->warnings();
#endif
}

svdagIsolatedSlabSource::~svdagIsolatedSlabSource() = default;

void svdagIsolatedSlabSource::readSlab(int32_t z0, int32_t nz, void* dst)
{
  this->checkSlab(z0, nz);
#ifdef SVDAG_ISOLATE
  const std::string what =
    "reading z-slices " + std::to_string(z0) + ".." + std::to_string(z0 + nz - 1);
  const Request request{ z0, nz };
  if (!sendAll(impl->fd, &request, sizeof request))
    throw svdagReadError(vtkErrorCode::FileFormatError,
      impl->fileName + ": " + impl->library + " " + impl->childFate() + " before " + what +
        " (corrupt file?)");
  impl->receiveStatus(what, this->Warnings);
  impl->receive(dst,
    size_t(nz) * size_t(this->Geometry.dims[0]) * size_t(this->Geometry.dims[1]) *
      size_t(this->sampleSize()),
    what);
#else
  impl->source->readSlab(z0, nz, dst);
  this->Warnings = impl->source->warnings();
#endif
}
