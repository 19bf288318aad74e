// Checklist items 21-34: the control unit's states, bit rates, bit-rate detection, filters and
// self reception.
using System.Collections.Generic;
using System.Threading;
using Ixxat.Vci3.Bal.Can;
using NUnit.Framework;

namespace Canemu.Tests
{
  public class ControlTests : DaemonFixture
  {
    protected override string Config
    {
      get
      {
        return Daemon.TwoAdapters +
            "\n[[device]]\nname = \"gamma\"\nmodel = \"ixxat-usb-to-can\"\ncontrollers = [\"can0\"]\n";
      }
    }

    static List<uint> Ids(List<CanMessage> got)
    {
      var ids = new List<uint>();
      foreach (var m in got) ids.Add(m.Identifier | (m.RemoteTransmissionRequest ? 0x80000000u : 0));
      return ids;
    }

    // Starts the receiver's line, lets the sender send `burst` and steps `ms`: what the receiver
    // got.
    static List<CanMessage> StartAndReceive(Line receiver, Line sender, double ms, params CanMessage[] burst)
    {
      receiver.Control.StartLine();
      sender.Writer.SendMessages(burst);
      T.Step(ms);
      return receiver.Data();
    }

    // A line of `device` whose 11-bit acceptance filter is closed (code and mask None), started.
    static Line StartedWithStdClosed(string device)
    {
      var line = new Line(device, start: false);
      line.Control.SetAccFilter(CanFilter.Std, CanAccCode.None, CanAccMask.None);
      line.Control.StartLine();
      return line;
    }

    static CanMessage Rtr(uint id)
    {
      var m = T.Msg(id);
      m.RemoteTransmissionRequest = true;
      return m;
    }

    [Test]
    public void Item21_UndefinedThenOfflineAfterInitLineThenOnline()
    {
      using (var bal = T.Bal("alpha"))
      using (var control = T.Open<ICanControl>(bal))
      {
        Assert.IsTrue(control.LineStatus.IsInInitMode);
        Assert.AreEqual(CanOperatingModes.Undefined, control.LineStatus.OperatingMode);
        var e = T.Throws(() => control.StartLine());
        Assert.AreEqual(0xE0010015u, e.ErrorCode);
        StringAssert.Contains("the line is not initialized; call InitLine (or DetectBaud) first", e.Message);
        control.InitLine(CanOperatingModes.Standard | CanOperatingModes.ErrFrame, CanBitrate.Cia125KBit);
        Assert.IsTrue(control.LineStatus.IsInInitMode, "offline");
        Assert.AreEqual(CanOperatingModes.Standard | CanOperatingModes.ErrFrame, control.LineStatus.OperatingMode);
        Assert.AreEqual(CanBitrate.Cia125KBit, control.LineStatus.Bitrate);
        control.StartLine();
        Assert.IsFalse(control.LineStatus.IsInInitMode, "online");
        control.StopLine();
        Assert.IsTrue(control.LineStatus.IsInInitMode);
        // DetectBaud leaves the line offline too (on a silent bus: not initialized).
        int found = 0;
        var detector = new Thread(() => found = control.DetectBaud(1, new[] { CanBitrate.Cia500KBit }));
        detector.Start();
        T.StepUntil(() => !detector.IsAlive);
        detector.Join();
        Assert.AreEqual(-1, found);
        T.Throws(() => control.StartLine());
      }
    }

    [Test]
    public void Item22_StopLineKeepsFiltersAndFifos()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.None, CanAccMask.None);
        alpha.Control.AddFilterIds(CanFilter.Std, 0x100 << 1, 0xFFF);
        alpha.Control.StartLine();
        beta.Send(T.Msg(0x100, 1));
        beta.Send(T.Msg(0x101, 2));
        T.Step(5);
        alpha.Control.StopLine();
        Assert.IsTrue(alpha.Writer.SendMessage(T.Msg(0x555, 5)), "queued while offline");
        T.Step(5);
        CollectionAssert.AreEqual(new uint[] { 0x100 }, Ids(alpha.Data()), "the receive FIFO kept its message");
        Assert.AreEqual(0, beta.Data().Count);
        alpha.Control.StartLine();
        beta.Send(T.Msg(0x100, 3));
        beta.Send(T.Msg(0x101, 4));
        T.Step(5);
        CollectionAssert.AreEqual(new uint[] { 0x100 }, Ids(alpha.Data()), "the filters are kept");
        CollectionAssert.AreEqual(new uint[] { 0x555 }, Ids(beta.Data()), "the transmit FIFO kept its message");
      }
    }

    [Test]
    public void Item23_ResetLineClearsTheFiltersKeepsTheFifosAndAbortsAFrame()
    {
      using (var beta = new Line("beta"))
      using (var gamma = new Line("gamma"))
      using (var alpha = StartedWithStdClosed("alpha"))
      {
        beta.Send(T.Msg(0x100, 1));
        T.Step(5);
        Assert.AreEqual(0, alpha.Data().Count, "filtered");
        gamma.Data();
        // A frame already on the wire when ResetLine comes completes (docs/vci.md: the manual's
        // "may" of a faulty telegram is not taken; docs/dotnet.md).
        alpha.Send(T.Msg(0x7FF, 1, 2, 3, 4, 5, 6, 7, 8));
        T.Step(0.1);
        alpha.Control.ResetLine();
        T.Step(5);
        var done = gamma.Data();
        Assert.AreEqual(1, done.Count, "the frame on the wire completed");
        Assert.AreEqual(5236u, done[0].TimeStamp, "its end, as without the reset");
        Assert.IsTrue(alpha.Control.LineStatus.IsInInitMode, "offline");
        beta.Send(T.Msg(0x101, 2));
        T.Step(5);
        alpha.Control.StartLine();
        beta.Send(T.Msg(0x102, 3));
        T.Step(5);
        CollectionAssert.AreEqual(new uint[] { 0x102 }, Ids(alpha.Data()), "the filter is open again");
      }
    }

    [Test]
    public void Item24_InitLineTakesSja1000RegistersAt16MHz()
    {
      // BTR0 0x01, BTR1 0x05: tq = 2 x 125 ns, 1 + 6 + 1 = 8 quanta: 500 kbit/s like 0x00/0x1C.
      var eight = new CanBitrate(0x01, 0x05);
      Assert.AreEqual(500000, eight.BitsPerSecond);
      Assert.AreEqual(8, eight.QuantaPerBit);
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", bitrate: eight))
      using (var gamma = new Line("gamma", bitrate: new CanBitrate(0x01, 0x1C)))  // 250 kbit/s
      {
        Assert.AreEqual(eight, alpha.Control.LineStatus.Bitrate);
        alpha.Send(T.Msg(0x321, 0x55));
        T.Step(5);
        CollectionAssert.AreEqual(new uint[] { 0x321 }, Ids(beta.Data()), "the same rate with other quanta");
        Assert.AreEqual(0, gamma.Data().Count, "250 kbit/s cannot read it");
        // SAM (bit 7 of BTR1): three samples, shown back as set.
        alpha.Control.StopLine();
        alpha.Control.InitLine(CanOperatingModes.Standard, new CanBitrate(0x00, 0x9C));
        Assert.AreEqual(new CanBitrate(0x00, 0x9C), alpha.Control.LineStatus.Bitrate);
      }
    }

    [Test]
    public void Item25_TheNinePresetsDecodeToTheirRates()
    {
      var presets = new[] { CanBitrate.Cia10KBit, CanBitrate.Cia20KBit, CanBitrate.Cia50KBit, CanBitrate.Cia125KBit,
                            CanBitrate.Cia250KBit, CanBitrate.Cia500KBit, CanBitrate.Cia800KBit, CanBitrate.Cia1000KBit,
                            CanBitrate._100KBit };
      var rates = new[] { 10000, 20000, 50000, 125000, 250000, 500000, 800000, 1000000, 100000 };
      var quanta = new[] { 16, 16, 16, 16, 16, 16, 10, 8, 16 };
      for (int i = 0; i < presets.Length; i++)
      {
        Assert.AreEqual(rates[i], presets[i].BitsPerSecond, presets[i].ToString());
        Assert.AreEqual(quanta[i], presets[i].QuantaPerBit);
      }
      Assert.AreEqual(8, CanBitrate.CiaBitRates.Length);
      Assert.AreEqual(CanBitrate.Cia125KBit, CanBitrate.CiaBitRates[3]);
      using (var bal = T.Bal("alpha"))
      using (var control = T.Open<ICanControl>(bal))
      {
        foreach (var p in presets)
        {
          control.InitLine(CanOperatingModes.Standard, p);
          Assert.AreEqual(p, control.LineStatus.Bitrate, "the controller takes " + p);
        }
      }
      // 800 kbit/s on the wire (10 quanta).
      using (var beta = new Line("beta", bitrate: CanBitrate.Cia800KBit))
      using (var alpha = new Line("alpha", bitrate: CanBitrate.Cia800KBit))
      {
        alpha.Send(T.Msg(0x80, 8));
        T.Step(2);
        CollectionAssert.AreEqual(new uint[] { 0x80 }, Ids(beta.Data()));
      }
    }

    [Test]
    public void Item26_DetectBaudFindsTheRateOrSaysMinusOne()
    {
      using (var gamma = new Line("gamma", bitrate: CanBitrate.Cia250KBit))
      using (var beta = new Line("beta", bitrate: CanBitrate.Cia250KBit))
      using (var list = T.Open<ICanScheduler>(beta.Bal))
      using (var bal = T.Bal("alpha"))
      using (var control = T.Open<ICanControl>(bal))
      {
        var cyclic = new CanCyclicTXMsg { Identifier = 0x2A0, DataLength = 1, CycleTicks = 1 };
        list.AddMessage(cyclic);
        list.StartMessage(cyclic);
        list.Resume();
        int found = -2;
        bool done = false;
        var detector = new Thread(() => { found = control.DetectBaud(100, CanBitrate.CiaBitRates); done = true; });
        detector.Start();
        T.StepUntil(() => done);
        detector.Join();
        Assert.AreEqual(4, found, "Cia250KBit");
        Assert.AreEqual(CanBitrate.Cia250KBit, control.LineStatus.Bitrate, "offline with the rate found");
        list.Suspend();
        T.Step(5);
        done = false;
        detector = new Thread(() => { found = control.DetectBaud(10, CanBitrate.CiaBitRates); done = true; });
        detector.Start();
        T.StepUntil(() => done);
        detector.Join();
        Assert.AreEqual(-1, found, "a silent bus");
      }
    }

    [Test]
    public void Item27_FilterChangesOnlyWhileOffline()
    {
      using (var alpha = new Line("alpha"))
      {
        var e = T.Throws(() => alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.All, CanAccMask.All));
        Assert.AreEqual(0xE0010015u, e.ErrorCode);
        StringAssert.Contains("the filters can change only while the line is offline (StopLine first)", e.Message);
        T.Throws(() => alpha.Control.AddFilterIds(CanFilter.Ext, 0x2, 0x3FFFFFFF));
        T.Throws(() => alpha.Control.RemFilterIds(CanFilter.Std, 0x2, 0xFFF));
        alpha.Control.StopLine();
        alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.All, CanAccMask.All);
        alpha.Control.AddFilterIds(CanFilter.Ext, 0x2, 0x3FFFFFFF);
        alpha.Control.RemFilterIds(CanFilter.Ext, 0x2, 0x3FFFFFFF);
        e = T.Throws(() => alpha.Control.SetAccFilter((CanFilter)3, 0u, 0u));
        StringAssert.Contains("select must be CanFilter.Std or CanFilter.Ext", e.Message);
      }
    }

    [Test]
    public void Item28_ElevenAndTwentyNineBitFiltersAreIndependentAndInitOpensBoth()
    {
      using (var beta = new Line("beta"))
      using (var alpha = StartedWithStdClosed("alpha"))
      {
        var ext = T.Msg(0x100, 1);
        ext.ExtendedFrameFormat = true;
        beta.Send(T.Msg(0x100, 1));
        beta.Send(ext);
        T.Step(5);
        var got = alpha.Data();
        Assert.AreEqual(1, got.Count);
        Assert.IsTrue(got[0].ExtendedFrameFormat, "only the 11-bit filter is closed");
        alpha.Control.StopLine();
        alpha.Control.InitLine(CanOperatingModes.Standard | CanOperatingModes.Extended, CanBitrate.Cia500KBit);
        alpha.Control.StartLine();
        beta.Send(T.Msg(0x100, 1));
        T.Step(5);
        Assert.AreEqual(1, alpha.Data().Count, "InitLine opened it again");
      }
    }

    [Test]
    public void Item29_CodeAndMaskNoneRejectEverything()
    {
      Assert.AreEqual(0x80000000u, (uint)CanAccCode.None);
      Assert.AreEqual(0xFFFFFFFFu, (uint)CanAccMask.None);
      Assert.AreEqual(0u, (uint)CanAccCode.All);
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.None, CanAccMask.None);
        alpha.Control.SetAccFilter(CanFilter.Ext, CanAccCode.None, CanAccMask.None);
        alpha.Control.StartLine();
        var ext = T.Msg(0x0, 1);
        ext.ExtendedFrameFormat = true;
        beta.Writer.SendMessages(new[] { T.Msg(0x0), Rtr(0x0), T.Msg(0x7FF), Rtr(0x7FF), ext });
        T.Step(5);
        Assert.AreEqual(0, alpha.Data().Count);
      }
    }

    [Test]
    public void Item30_AcceptanceFilterThenIdListThenDrop()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        alpha.Control.SetAccFilter(CanFilter.Std, 0x100 << 1, 0xFFF);
        alpha.Control.AddFilterIds(CanFilter.Std, 0x300 << 1, 0xFFF);
        var got = StartAndReceive(alpha, beta, 5, T.Msg(0x100), T.Msg(0x200), T.Msg(0x300));
        CollectionAssert.AreEqual(new uint[] { 0x100, 0x300 }, Ids(got));
        Assert.AreEqual(CanAcceptReason.AcceptanceFilter, got[0].AcceptReason);
        Assert.AreEqual(CanAcceptReason.FilterList, got[1].AcceptReason);
      }
    }

    [Test]
    public void Item31_TheManualsExampleAcceptsExactly100hTo103h()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        alpha.Control.SetAccFilter(CanFilter.Std, 0x200, 0xFF9);
        var got = StartAndReceive(alpha, beta, 10, T.Msg(0xFF), T.Msg(0x100), T.Msg(0x101), T.Msg(0x102),
                                  T.Msg(0x103), T.Msg(0x104), Rtr(0x101), T.Msg(0x500));
        CollectionAssert.AreEqual(new uint[] { 0x100, 0x101, 0x102, 0x103 }, Ids(got));
      }
    }

    [Test]
    public void Item32_AddFilterIdsListsEveryMatchingKeyAndRemFilterIdsTakesThemOut()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        var burst = new[] { T.Msg(0xFF), T.Msg(0x100), T.Msg(0x101), T.Msg(0x102), T.Msg(0x103), T.Msg(0x104), Rtr(0x101), Rtr(0x7FF) };
        alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.None, CanAccMask.None);
        alpha.Control.AddFilterIds(CanFilter.Std, 0x200, 0xFF9);
        alpha.Control.AddFilterIds(CanFilter.Std, (0x7FF << 1) | 1, 0xFFF);  // one key: RTR 7FFh
        CollectionAssert.AreEqual(new uint[] { 0x100, 0x101, 0x102, 0x103, 0x800007FF },
                                  Ids(StartAndReceive(alpha, beta, 10, burst)));
        alpha.Control.StopLine();
        alpha.Control.RemFilterIds(CanFilter.Std, 0x202, 0xFFF);  // 101h
        CollectionAssert.AreEqual(new uint[] { 0x100, 0x102, 0x103, 0x800007FF },
                                  Ids(StartAndReceive(alpha, beta, 10, burst)));
      }
    }

    [Test]
    public void Item33_NoneLeavesTheListAloneAllMakesItIrrelevant()
    {
      using (var beta = new Line("beta"))
      using (var alpha = new Line("alpha", start: false))
      {
        alpha.Control.AddFilterIds(CanFilter.Std, 0x300 << 1, 0xFFF);
        alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.None, CanAccMask.None);
        var got = StartAndReceive(alpha, beta, 5, T.Msg(0x100), T.Msg(0x300));
        CollectionAssert.AreEqual(new uint[] { 0x300 }, Ids(got), "only the list admits");
        alpha.Control.StopLine();
        alpha.Control.SetAccFilter(CanFilter.Std, CanAccCode.All, CanAccMask.All);
        got = StartAndReceive(alpha, beta, 5, T.Msg(0x100), T.Msg(0x300));
        CollectionAssert.AreEqual(new uint[] { 0x100, 0x300 }, Ids(got), "everything passes");
        Assert.AreEqual(CanAcceptReason.AcceptanceFilter, got[1].AcceptReason, "the list is not asked");
      }
    }

    [Test]
    public void Item34_SelfReceptionEchoesPastTheFilter()
    {
      using (var beta = new Line("beta"))
      using (var alpha = StartedWithStdClosed("alpha"))
      {
        var m = T.Msg(0x123, 1, 2);
        m.SelfReceptionRequest = true;
        alpha.Send(m);
        alpha.Send(T.Msg(0x124, 3));
        T.Step(5);
        var echo = alpha.Data();
        Assert.AreEqual(1, echo.Count, "only the frame that asked for it");
        Assert.AreEqual(0x123u, echo[0].Identifier);
        Assert.IsTrue(echo[0].SelfReceptionRequest);
        Assert.AreEqual(2, echo[0][1]);
        var got = beta.Data();
        CollectionAssert.AreEqual(new uint[] { 0x123, 0x124 }, Ids(got));
        Assert.IsFalse(got[0].SelfReceptionRequest);
        Assert.AreEqual(got[0].TimeStamp, echo[0].TimeStamp, "echoed at the end of its transmission");
      }
    }
  }
}
