#pragma once
// The scheduling priority of threads whose work waits in a queue (the dense reconstruction's
// meshing and fusion): at a lower priority they run on the time the SLAM's own threads leave
// on the cores instead of taking it from them (docs/PERFORMANCE.md, "The dense threads' lower
// priority"). Linux gives each thread its own nice value; elsewhere nothing changes.
namespace vitamin_e {

inline constexpr int kMaxNice = 19;
// A nice increment this module takes: [0, kMaxNice].
inline constexpr bool isNiceIncrement(int increment) { return increment >= 0 && increment <= kMaxNice; }

// Raises the calling thread's nice value by `increment` (at most to kMaxNice): it then runs
// below the thread that created it, whatever that one's nice value. 0 leaves it as it is.
// Returns false where the system does not allow it (the thread keeps its priority).
// Throws std::invalid_argument for an increment outside [0, kMaxNice].
bool lowerCurrentThreadPriority(int increment);

// The calling thread's nice value (0 where the system has none).
int currentThreadNice();

}  // namespace vitamin_e
