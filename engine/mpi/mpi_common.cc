#include "engine/mpi/mpi_common.h"

#include <algorithm>
#include <thread>

#include "engine/common/errors.h"

namespace gesweep::mpi {
void CheckMpi(int code, const char* what) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  throw MpiError(std::string("MPI error in ") + what + ": " +
                 std::string(text, static_cast<std::size_t>(length)));
}

void EnsureMpi() {
  int initialized = 0;
  MPI_Initialized(&initialized);
  if (initialized) return;
  int provided = 0;
  CheckMpi(MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  GESWEEP_DEMAND(provided >= MPI_THREAD_FUNNELED);
}

void WaitPolling(MPI_Request& request, const char* what) {
  for (;;) {
    int done = 0;
    CheckMpi(MPI_Test(&request, &done, MPI_STATUS_IGNORE), what);
    if (done) return;
    std::this_thread::sleep_for(kIdlePoll);
  }
}

std::vector<std::string> GatherText(const std::string& text, int ranks) {
  const int length = static_cast<int>(text.size());
  std::vector<int> lengths(static_cast<std::size_t>(ranks)), offsets(static_cast<std::size_t>(ranks));
  CheckMpi(MPI_Gather(&length, 1, MPI_INT, lengths.data(), 1, MPI_INT, 0, MPI_COMM_WORLD), "MPI_Gather");
  int total = 0;
  for (int r = 0; r < ranks; ++r) {
    offsets[static_cast<std::size_t>(r)] = total;
    total += lengths[static_cast<std::size_t>(r)];
  }
  std::vector<char> all(static_cast<std::size_t>(std::max(total, 1)));
  CheckMpi(MPI_Gatherv(text.data(), length, MPI_CHAR, all.data(), lengths.data(), offsets.data(), MPI_CHAR, 0,
                       MPI_COMM_WORLD),
           "MPI_Gatherv");
  std::vector<std::string> texts(static_cast<std::size_t>(ranks));
  for (int r = 0; r < ranks; ++r) {
    texts[static_cast<std::size_t>(r)].assign(all.data() + offsets[static_cast<std::size_t>(r)],
                                              static_cast<std::size_t>(lengths[static_cast<std::size_t>(r)]));
  }
  return texts;
}

int AgreeOnError(int code, const std::string& text, int rank, int ranks, std::string* first) {
  int worst = 0;
  CheckMpi(MPI_Allreduce(&code, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), "MPI_Allreduce");
  if (worst == 0) return 0;
  const std::vector<std::string> texts = GatherText(code == worst ? text : std::string(), ranks);
  if (rank == 0) {
    for (const auto& candidate : texts) {
      if (!candidate.empty()) {
        *first = candidate;
        break;
      }
    }
  }
  return worst;
}

}  // namespace gesweep::mpi
