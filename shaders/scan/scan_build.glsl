// The build's workgroup shape (scan_layout.h): EVF_SCAN_WIDE selects 16 invocations of 256
// elements (CPU drivers), else 256 of 16; the block is kScanBlock elements either way.
#ifdef EVF_SCAN_WIDE
#define EVF_SCAN_GROUP kScanGroupSizeWide
#define EVF_SCAN_ITEMS kScanItemsWide
#else
#define EVF_SCAN_GROUP kScanGroupSize
#define EVF_SCAN_ITEMS kScanItems
#endif
