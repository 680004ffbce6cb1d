// The build's digit width and workgroup size (sort_layout.h): EVF_SORT_WIDE selects 8-bit digits.
#ifdef EVF_SORT_WIDE
#define EVF_SORT_BINS kSortBinsWide
#define EVF_SORT_GROUP kSortGroupSizeWide
#else
#define EVF_SORT_BINS kSortBins
#define EVF_SORT_GROUP kSortGroupSize
#endif
