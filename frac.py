import sys, numpy as np
from PIL import Image
a=np.asarray(Image.open(sys.argv[1]).convert('RGB')).astype(int)
b=np.asarray(Image.open(sys.argv[2]).convert('RGB')).astype(int)
d=np.abs(a-b).max(axis=2)
for t in [4,8,16]:
    print(f"{sys.argv[1]}: fraction of pixels differing from background by > {t}/255: {(d>t).mean()*100:.1f} %")
