#include "engine/risk/risk_archive.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <set>

#include "engine/archive/archive_error.h"
#include "engine/common/errors.h"
#include "engine/disturbance/run_noise.h"

namespace gesweep::risk {
namespace {

constexpr char kJournalMagic[] = "GESWEEP-RISK-JOURNAL-2\n";
constexpr std::size_t kMagicLength = sizeof(kJournalMagic) - 1;
constexpr std::size_t kHeaderLength = kMagicLength + 8 + 4;
constexpr std::uint32_t kMaxRecord = 1u << 26;  // 64 MiB: far above any record

std::uint64_t Checksum(const unsigned char* data, std::size_t size) {
  std::uint64_t hash = 0x6a6f75726e616c31ULL;  // "journal1"
  std::size_t i = 0;
  for (; i + 8 <= size; i += 8) {
    std::uint64_t word;
    std::memcpy(&word, data + i, 8);
    hash = SplitMix64Mix(hash ^ SplitMix64Mix(word + 1));
  }
  std::uint64_t tail = size;
  for (; i < size; ++i) tail = (tail << 8) | data[i];
  return SplitMix64Mix(hash ^ SplitMix64Mix(tail + 1));
}

template <class T>
void Put(std::vector<unsigned char>& out, const T& value) {
  const auto* p = reinterpret_cast<const unsigned char*>(&value);
  out.insert(out.end(), p, p + sizeof(T));
}

template <class T>
bool Get(const unsigned char*& p, const unsigned char* end, T& value) {
  if (static_cast<std::size_t>(end - p) < sizeof(T)) return false;
  std::memcpy(&value, p, sizeof(T));
  p += sizeof(T);
  return true;
}

void WriteAll(int fd, const unsigned char* data, std::size_t size, const std::filesystem::path& path) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw ArchiveError("write " + path.string() + ": " + std::strerror(errno));
    }
    data += n;
    size -= static_cast<std::size_t>(n);
  }
}

std::vector<unsigned char> EncodeRecord(const Evaluation& e) {
  std::vector<unsigned char> payload;
  for (const std::int32_t v :
       {e.key.cell, e.key.limit, e.key.repetition, e.key.level, e.key.chain, e.key.step})
    Put(payload, v);
  Put(payload, e.status);
  Put(payload, e.g);
  Put(payload, static_cast<std::uint32_t>(e.message.size()));
  payload.insert(payload.end(), e.message.begin(), e.message.end());
  Put(payload, static_cast<std::uint32_t>(e.values.size()));
  for (const double v : e.values) Put(payload, v);
  std::vector<unsigned char> record;
  Put(record, static_cast<std::uint32_t>(payload.size()));
  record.insert(record.end(), payload.begin(), payload.end());
  Put(record, Checksum(payload.data(), payload.size()));
  return record;
}

bool DecodeRecord(const unsigned char* p, const unsigned char* end, std::uint32_t value_count,
                  Evaluation& e) {
  std::int32_t* keys[] = {&e.key.cell,  &e.key.limit, &e.key.repetition,
                          &e.key.level, &e.key.chain, &e.key.step};
  for (std::int32_t* k : keys) {
    if (!Get(p, end, *k)) return false;
  }
  std::uint32_t length = 0, count = 0;
  if (!Get(p, end, e.status) || !Get(p, end, e.g) || !Get(p, end, length)) return false;
  if (static_cast<std::size_t>(end - p) < length) return false;
  e.message.assign(reinterpret_cast<const char*>(p), length);
  p += length;
  if (!Get(p, end, count) || count != value_count) return false;
  e.values.resize(count);
  for (double& v : e.values) {
    if (!Get(p, end, v)) return false;
  }
  return p == end;
}

}  // namespace

std::filesystem::path JournalPath(const std::filesystem::path& archive) {
  return std::filesystem::path(archive.string() + ".journal");
}

JournalWriter::JournalWriter(const std::filesystem::path& path, std::uint64_t fingerprint,
                             std::uint32_t value_count, std::uint64_t resume_length)
    : path_(path) {
  if (resume_length > 0) {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd_ < 0) throw ArchiveError("open " + path.string() + ": " + std::strerror(errno));
    if (::ftruncate(fd_, static_cast<off_t>(resume_length)) != 0 ||
        ::lseek(fd_, static_cast<off_t>(resume_length), SEEK_SET) < 0) {
      const int error = errno;
      ::close(fd_);
      throw ArchiveError("cut " + path.string() + ": " + std::strerror(error));
    }
    return;
  }
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (fd_ < 0) throw ArchiveError("create " + path.string() + ": " + std::strerror(errno));
  std::vector<unsigned char> header(kJournalMagic, kJournalMagic + kMagicLength);
  Put(header, fingerprint);
  Put(header, value_count);
  WriteAll(fd_, header.data(), header.size(), path_);
  if (::fdatasync(fd_) != 0) throw ArchiveError("sync " + path.string() + ": " + std::strerror(errno));
}

JournalWriter::~JournalWriter() {
  if (fd_ >= 0) ::close(fd_);
}

std::vector<unsigned char> EncodeEvaluations(std::span<const Evaluation> evaluations) {
  std::vector<unsigned char> bytes;
  for (const auto& e : evaluations) {
    const auto record = EncodeRecord(e);
    bytes.insert(bytes.end(), record.begin(), record.end());
  }
  return bytes;
}

bool DecodeEvaluations(std::span<const unsigned char> bytes, std::uint32_t value_count,
                       std::vector<Evaluation>& out) {
  const unsigned char* p = bytes.data();
  const unsigned char* end = p + bytes.size();
  while (p < end) {
    std::uint32_t length = 0;
    std::uint64_t checksum = 0;
    if (!Get(p, end, length) || static_cast<std::size_t>(end - p) < length + 8u) return false;
    const unsigned char* payload = p;
    p += length;
    Get(p, end, checksum);
    Evaluation e;
    if (checksum != Checksum(payload, length) || !DecodeRecord(payload, payload + length, value_count, e))
      return false;
    out.push_back(std::move(e));
  }
  return true;
}

void JournalWriter::Append(std::span<const Evaluation> evaluations) {
  const std::vector<unsigned char> bytes = EncodeEvaluations(evaluations);
  WriteAll(fd_, bytes.data(), bytes.size(), path_);
  if (::fdatasync(fd_) != 0) throw ArchiveError("sync " + path_.string() + ": " + std::strerror(errno));
}

JournalContents ReadJournal(const std::filesystem::path& path, std::uint64_t fingerprint,
                            std::uint32_t value_count) {
  const std::string source = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(source, "", "", "a journal of `gesweep risk` to resume from: it cannot be read");
  const std::vector<unsigned char> data((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (data.size() < kHeaderLength || std::memcmp(data.data(), kJournalMagic, kMagicLength) != 0) {
    throw InputError(source, "", "", "a journal of `gesweep risk` (it does not start as one)");
  }
  const unsigned char* p = data.data() + kMagicLength;
  const unsigned char* end = data.data() + data.size();
  std::uint64_t stored_fingerprint = 0;
  std::uint32_t stored_count = 0;
  Get(p, end, stored_fingerprint);
  Get(p, end, stored_count);
  if (stored_fingerprint != fingerprint || stored_count != value_count) {
    throw InputError(
        source, "", "",
        "the journal of this study and [subset] table: it was written for another study, spec or "
        "engine (delete it, or resume with the study it was made with)");
  }
  JournalContents contents;
  contents.valid_length = kHeaderLength;
  while (p < end) {
    const unsigned char* start = p;
    std::uint32_t length = 0;
    if (!Get(p, end, length) || length > kMaxRecord || static_cast<std::size_t>(end - p) < length + 8u) {
      contents.torn_tail = true;  // a record cut by the kill: the batch in flight
      break;
    }
    std::uint64_t checksum = 0;
    const unsigned char* payload = p;
    p += length;
    Get(p, end, checksum);
    Evaluation e;
    if (checksum != Checksum(payload, length) || !DecodeRecord(payload, payload + length, value_count, e)) {
      if (p == end) {  // the last record, torn inside
        contents.torn_tail = true;
        break;
      }
      throw InputError(source, "", "",
                       "a journal whose records are whole: record " + std::to_string(contents.records + 1) +
                           " (at byte " + std::to_string(start - data.data()) + ") is damaged");
    }
    if (!contents.evaluations.emplace(e.key, e).second) {
      throw InputError(source, "", "",
                       "a journal with each landing once: record " + std::to_string(contents.records + 1) +
                           " repeats a tag");
    }
    ++contents.records;
    contents.valid_length = static_cast<std::uint64_t>(p - data.data());
  }
  return contents;
}

}  // namespace gesweep::risk
