#include "engine/mpi/risk_exchange.h"

#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <cstring>

#include "engine/common/errors.h"
#include "engine/mpi/mpi_common.h"

namespace gesweep {

using mpi::CheckMpi;

MpiBatchExchange::MpiBatchExchange() {
  mpi::EnsureMpi();
  CheckMpi(MPI_Comm_rank(MPI_COMM_WORLD, &rank_), "MPI_Comm_rank");
  CheckMpi(MPI_Comm_size(MPI_COMM_WORLD, &ranks_), "MPI_Comm_size");
}

std::vector<std::vector<unsigned char>> MpiBatchExchange::AllGather(std::span<const unsigned char> mine) {
  const auto count = static_cast<std::size_t>(ranks_);
  std::vector<int> lengths(count), offsets(count);
  const int length = static_cast<int>(mine.size());
  MPI_Request request = MPI_REQUEST_NULL;
  CheckMpi(MPI_Iallgather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, MPI_COMM_WORLD, &request),
           "MPI_Iallgather");
  mpi::WaitPolling(request, "MPI_Iallgather");
  std::size_t total = 0;
  for (std::size_t r = 0; r < count; ++r) {
    GESWEEP_DEMAND(total + static_cast<std::size_t>(lengths[r]) <= static_cast<std::size_t>(INT32_MAX));
    offsets[r] = static_cast<int>(total);
    total += static_cast<std::size_t>(lengths[r]);
  }
  std::vector<unsigned char> all(std::max<std::size_t>(total, 1));
  CheckMpi(MPI_Iallgatherv(mine.data(), length, MPI_BYTE, all.data(), lengths.data(), offsets.data(),
                           MPI_BYTE, MPI_COMM_WORLD, &request),
           "MPI_Iallgatherv");
  mpi::WaitPolling(request, "MPI_Iallgatherv");
  std::vector<std::vector<unsigned char>> out(count);
  for (std::size_t r = 0; r < count; ++r)
    out[r].assign(all.begin() + offsets[r], all.begin() + offsets[r] + lengths[r]);
  return out;
}

std::vector<unsigned char> MpiBatchExchange::Broadcast(std::vector<unsigned char> bytes) const {
  std::uint64_t size = bytes.size();
  CheckMpi(MPI_Bcast(&size, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD), "MPI_Bcast");
  bytes.resize(size);
  // In pieces below 2^31 bytes (MPI's int counts).
  constexpr std::uint64_t kPiece = 1ULL << 30;
  for (std::uint64_t at = 0; at < size; at += kPiece) {
    const int n = static_cast<int>(std::min(kPiece, size - at));
    CheckMpi(MPI_Bcast(bytes.data() + at, n, MPI_BYTE, 0, MPI_COMM_WORLD), "MPI_Bcast");
  }
  return bytes;
}

std::int64_t MpiBatchExchange::Max(std::int64_t value) const {
  std::int64_t largest = 0;
  CheckMpi(MPI_Allreduce(&value, &largest, 1, MPI_INT64_T, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return largest;
}

bool MpiBatchExchange::Same(std::uint64_t value) const {
  std::uint64_t low = 0, high = 0;
  CheckMpi(MPI_Allreduce(&value, &low, 1, MPI_UINT64_T, MPI_MIN, MPI_COMM_WORLD), "MPI_Allreduce");
  CheckMpi(MPI_Allreduce(&value, &high, 1, MPI_UINT64_T, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  return low == high;
}

int MpiBatchExchange::AgreeOnError(int code, const std::string& text, std::string* first) const {
  return mpi::AgreeOnError(code, text, rank_, ranks_, first);
}

}  // namespace gesweep
