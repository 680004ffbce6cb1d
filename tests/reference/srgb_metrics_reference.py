#!/usr/bin/python3
# Independent reference values for tests/test_metrics.cpp: the same procedural 8-bit images,
# scored by scikit-image (Debian: python3-skimage). Run: /usr/bin/python3 this_file
import numpy as np
from skimage.metrics import peak_signal_noise_ratio, structural_similarity

W, H, C = 40, 32, 3
y, x, c = np.meshgrid(np.arange(H), np.arange(W), np.arange(C), indexing="ij")
a = (x * 7 + y * 13 + c * 31 + (x * y) % 17) % 256
b = np.clip(a + ((x * 3 + y * 5 + c) % 11) - 5, 0, 255)
d = np.clip((a // 2) + 40 + ((x + 2 * y + 3 * c) % 7) * 9, 0, 255)
for name, u, v in (("a_b", a, b), ("a_d", a, d)):
    u8, v8 = u.astype(np.uint8), v.astype(np.uint8)
    psnr = peak_signal_noise_ratio(u8, v8, data_range=255)
    ssim = structural_similarity(u8, v8, gaussian_weights=True, sigma=1.5, use_sample_covariance=False,
                                 data_range=255, channel_axis=-1)
    print(f"{name}: psnr {psnr:.10f} ssim {ssim:.10f}")
