// Lists over the frames of an exposure, for kernels built once per frame count F =
// EVF_FRAME_COUNT (2..9): EVF_FRAMES(X) expands X(k) for each frame k, EVF_FRAMES_BUT_LAST(X) for
// k = 0 .. F-2. With constant indices every per-frame value stays in registers and every
// per-frame binding has a name of its own.
#ifndef EVF_FRAME_COUNT
#error EVF_FRAME_COUNT (the exposure's frame count) must be defined
#endif
#if EVF_FRAME_COUNT == 2
#define EVF_FRAMES_BUT_LAST(X) X(0)
#define EVF_FRAMES(X) X(0) X(1)
#elif EVF_FRAME_COUNT == 3
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1)
#define EVF_FRAMES(X) X(0) X(1) X(2)
#elif EVF_FRAME_COUNT == 4
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1) X(2)
#define EVF_FRAMES(X) X(0) X(1) X(2) X(3)
#elif EVF_FRAME_COUNT == 5
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1) X(2) X(3)
#define EVF_FRAMES(X) X(0) X(1) X(2) X(3) X(4)
#elif EVF_FRAME_COUNT == 6
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1) X(2) X(3) X(4)
#define EVF_FRAMES(X) X(0) X(1) X(2) X(3) X(4) X(5)
#elif EVF_FRAME_COUNT == 7
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1) X(2) X(3) X(4) X(5)
#define EVF_FRAMES(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6)
#elif EVF_FRAME_COUNT == 8
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6)
#define EVF_FRAMES(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6) X(7)
#elif EVF_FRAME_COUNT == 9
#define EVF_FRAMES_BUT_LAST(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6) X(7)
#define EVF_FRAMES(X) X(0) X(1) X(2) X(3) X(4) X(5) X(6) X(7) X(8)
#else
#error EVF_FRAME_COUNT must be 2 .. 9
#endif
